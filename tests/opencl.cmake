# OpenCL engine test wiring (included by tests/CMakeLists.txt).
#
# voxmesh_opencl_fallback: the ICD loader pointed at an empty vendors directory, so that no
# OpenCL platform exists; Backend::Auto/Hybrid must mesh on the CPU with a warning and
# Backend::OpenCL must throw a clear Error.
set(VOXMESH_EMPTY_ICD_DIR ${CMAKE_CURRENT_BINARY_DIR}/empty-opencl-vendors)
file(MAKE_DIRECTORY ${VOXMESH_EMPTY_ICD_DIR})
add_test(NAME voxmesh_opencl_fallback COMMAND voxmesh_tests "[fallback]")
set_tests_properties(voxmesh_opencl_fallback PROPERTIES
  ENVIRONMENT "OCL_ICD_VENDORS=${VOXMESH_EMPTY_ICD_DIR};OCL_ICD_FILENAMES=;${VOXMESH_TEST_ENV}")

# Sanitizers: the [opencl] tests and this fallback test run clean on PoCL 3.1 (Debian 12)
# under -DVOXMESH_SANITIZE=ON. When PoCL compiles a kernel variant for the first time (empty
# cache), LeakSanitizer reports memory PoCL's LLVM keeps; tests/lsan.supp suppresses those
# frames of libpocl/libLLVM only. On a cold cache LeakSanitizer itself can also abort at exit
# ("LeakSanitizer has encountered a fatal error") while PoCL's compiler threads wind down;
# .ci/run therefore runs the sanitizer suite after the Release suite, which warms the cache
# with the very same kernel builds. The one "1 error generated." on stderr is PoCL compiling the
# deliberately broken kernel of the build-failure test.
# The [opencl] tests skip with a visible WARN when no OpenCL device exists. PoCL caches
# compiled kernels (~/.cache/pocl); the first run of every kernel variant compiles (~1 s each).

# voxmesh_opencl_faults: the [.clfault] test with tests/cl_fault_layer loaded into the ICD
# loader (OPENCL_LAYERS, ocl-icd 2.3+), which fails chosen kernel launches and buffer
# allocations as a device out of memory would: PoCL on the host never does.
if(VOXMESH_WITH_OPENCL)
  add_library(voxmesh_cl_fault_layer MODULE ${CMAKE_CURRENT_SOURCE_DIR}/cl_fault_layer/cl_fault_layer.cpp)
  target_include_directories(voxmesh_cl_fault_layer PRIVATE ${OpenCL_INCLUDE_DIRS})
  target_link_libraries(voxmesh_cl_fault_layer PRIVATE voxmesh_warnings)
  add_dependencies(voxmesh_tests voxmesh_cl_fault_layer)
  add_test(NAME voxmesh_opencl_faults COMMAND voxmesh_tests "[clfault]")
  set_tests_properties(voxmesh_opencl_faults PROPERTIES
    ENVIRONMENT "OPENCL_LAYERS=$<TARGET_FILE:voxmesh_cl_fault_layer>;${VOXMESH_TEST_ENV}")
  # The randomized [stress] cases again, each failing one drawn OpenCL call as out of memory.
  add_test(NAME voxmesh_opencl_faults_stress COMMAND voxmesh_tests "[stress]")
  set_tests_properties(voxmesh_opencl_faults_stress PROPERTIES
    ENVIRONMENT "OPENCL_LAYERS=$<TARGET_FILE:voxmesh_cl_fault_layer>;VOXMESH_STRESS_ITERATIONS=150;${VOXMESH_TEST_ENV}")
endif()
