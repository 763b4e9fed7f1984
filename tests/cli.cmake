# The CLI tests run the built `voxmesh` binary; they are compiled in only when it exists.
if(TARGET voxmesh_cli)
  target_compile_definitions(voxmesh_tests PRIVATE VOXMESH_CLI_PATH="$<TARGET_FILE:voxmesh_cli>")
  add_dependencies(voxmesh_tests voxmesh_cli)
endif()
