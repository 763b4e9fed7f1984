# The C API and the Python package (included by tests/CMakeLists.txt when libvoxmesh_c is built).
if(TARGET voxmesh_c)
  # The Catch2 tests compare the C API with the C++ one, through the shared library.
  target_link_libraries(voxmesh_tests PRIVATE voxmesh_c)
  target_compile_definitions(voxmesh_tests PRIVATE VOXMESH_TEST_C_API=1)

  # From C itself: C99, every warning an error.
  add_executable(c_api_program c_api_program.c)
  target_link_libraries(c_api_program PRIVATE voxmesh_c m)
  set_target_properties(c_api_program PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
  target_compile_options(c_api_program PRIVATE -Wall -Wextra -Wpedantic -Werror)
  if(VOXMESH_SANITIZE)
    target_compile_options(c_api_program PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer)
    target_link_options(c_api_program PRIVATE -fsanitize=address,undefined)
  endif()
  set(_capi_scratch ${CMAKE_CURRENT_BINARY_DIR}/c-api-scratch)
  file(MAKE_DIRECTORY ${_capi_scratch})
  add_test(NAME voxmesh_c_api COMMAND c_api_program ${_capi_scratch} ${CMAKE_CURRENT_SOURCE_DIR}/data/headsq.nrrd)
  set_tests_properties(voxmesh_c_api PROPERTIES ENVIRONMENT "${VOXMESH_TEST_ENV}")

  # The library exports the C API and nothing else (the C++ library inside stays private).
  add_test(NAME voxmesh_c_api_exports
           COMMAND sh -c "nm -D --defined-only \"$1\" | awk '$3 !~ /^voxmesh_/ {print; bad=1} END {exit bad}'"
                   sh $<TARGET_FILE:voxmesh_c>)

  # The Python package, with Debian's python3 and numpy (scripts/install-deps.sh installs
  # python3-numpy). Not under sanitizers: a Python interpreter cannot load an ASan library
  # unless the runtime is preloaded.
  if(NOT VOXMESH_SANITIZE)
    find_program(VOXMESH_TEST_PYTHON NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH)
    if(VOXMESH_TEST_PYTHON)
      # test_python.py: the package against the mesh's properties and the CLI.
      # test_python_skimage.py: voxmesh.marching_cubes against its own expectations, and against
      # scikit-image where python3-skimage is installed (those cases skip without it).
      foreach(_script python python_skimage)
        add_test(NAME voxmesh_${_script} COMMAND ${VOXMESH_TEST_PYTHON} ${CMAKE_CURRENT_SOURCE_DIR}/test_${_script}.py)
        set_tests_properties(voxmesh_${_script} PROPERTIES SKIP_RETURN_CODE 77 ENVIRONMENT
          "PYTHONPATH=${PROJECT_BINARY_DIR}/python;VOXMESH_TEST_DATA=${CMAKE_CURRENT_SOURCE_DIR}/data;VOXMESH_TEST_SCRATCH=${_capi_scratch};VOXMESH_CLI=$<$<TARGET_EXISTS:voxmesh_cli>:$<TARGET_FILE:voxmesh_cli>>")
      endforeach()
    endif()
  endif()
endif()
