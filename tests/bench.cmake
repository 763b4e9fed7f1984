# The benchmark CLI's tests run the built voxmesh-bench on tiny volumes (what it reports, not
# how fast); they are compiled in only when it is built.
if(TARGET voxmesh_bench)
  target_compile_definitions(voxmesh_tests PRIVATE VOXMESH_BENCH_PATH="$<TARGET_FILE:voxmesh_bench>")
  add_dependencies(voxmesh_tests voxmesh_bench)
endif()
