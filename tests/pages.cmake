# Without huge pages (included by tests/CMakeLists.txt).
#
# VOXMESH_HUGE_PAGES=off stops the library advising huge pages (src/core/huge_pages.hpp); the
# [pages] tests check that the advice follows it and that the array sizing, the prefault and
# the shares of fresh pages work the same in small pages.
add_test(NAME voxmesh_pages_without_huge_pages COMMAND voxmesh_tests "[pages]")
set_tests_properties(voxmesh_pages_without_huge_pages PROPERTIES ENVIRONMENT "VOXMESH_HUGE_PAGES=off;${VOXMESH_TEST_ENV}")
