# Portable code paths (included by tests/CMakeLists.txt).
#
# On a processor with AVX2 the engine runs its AVX2 row packers and its AVX2/BMI copy of the
# generator; VOXMESH_ISA=portable turns both off. The [core] tests compare the CPU engine with
# the oracle, so running them again this way checks the portable paths give the same meshes.
add_test(NAME voxmesh_core_portable_isa COMMAND voxmesh_tests "[core]")
set_tests_properties(voxmesh_core_portable_isa PROPERTIES ENVIRONMENT "VOXMESH_ISA=portable;${VOXMESH_TEST_ENV}")

# POPCNT without AVX2 (an x86-64-v2 processor): classify's POPCNT copy with the portable
# packers and generator, a mix that neither the AVX2 run nor the portable one takes.
add_test(NAME voxmesh_core_popcnt_isa COMMAND voxmesh_tests "[core]~[large]~[memory]")
set_tests_properties(voxmesh_core_popcnt_isa PROPERTIES ENVIRONMENT "VOXMESH_ISA=popcnt;${VOXMESH_TEST_ENV}")

# The voxelizer's distance rows have an AVX2 copy too (src/voxelize/triangle_rows.cpp); its
# tests compare every sample with a brute-force oracle, so they check the portable rows.
add_test(NAME voxmesh_voxelize_portable_isa COMMAND voxmesh_tests "[voxelize]")
set_tests_properties(voxmesh_voxelize_portable_isa PROPERTIES ENVIRONMENT "VOXMESH_ISA=portable;${VOXMESH_TEST_ENV}")
