# OpenCL engine test wiring (included by tests/CMakeLists.txt).
#
# voxmesh_opencl_fallback: the ICD loader pointed at an empty vendors directory, so that no
# OpenCL platform exists; Backend::Auto/Hybrid must mesh on the CPU with a warning and
# Backend::OpenCL must throw a clear Error.
set(VOXMESH_EMPTY_ICD_DIR ${CMAKE_CURRENT_BINARY_DIR}/empty-opencl-vendors)
file(MAKE_DIRECTORY ${VOXMESH_EMPTY_ICD_DIR})
add_test(NAME voxmesh_opencl_fallback COMMAND voxmesh_tests "[fallback]")
set_tests_properties(voxmesh_opencl_fallback PROPERTIES
  ENVIRONMENT "OCL_ICD_VENDORS=${VOXMESH_EMPTY_ICD_DIR};OCL_ICD_FILENAMES=")
