// The thirty-seventh session's timing of keep_largest_components and analyze_topology on an
// extract of a built-in u8 field (2 threads by default), medians of ROUNDS; built and run as
// queries.cpp is: /tmp/klc_old gyroid 512 15; /tmp/klc_new gyroid 512 15; ... (mesh_ops.txt).
#include <voxmesh/voxmesh.hpp>
#include <voxmesh/fields.hpp>
#include <chrono>
#include <cstdio>
#include <algorithm>
#include <vector>
static double now(){return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();}
int main(int argc,char**argv){
  auto f=voxmesh::make_field(voxmesh::parse_field(argc>1?argv[1]:"gyroid"),argc>2?atoi(argv[2]):512,voxmesh::ScalarType::U8,1);
  voxmesh::Options o; o.iso=f.iso; auto m=voxmesh::extract(f.volume.view(),o);
  std::vector<double> tk,ta;
  for(int r=0;r<(argc>3?atoi(argv[3]):9);++r){
    double t0=now(); auto k=voxmesh::keep_largest_components(m,1); double t1=now();
    auto t=voxmesh::analyze_topology(m); double t2=now();
    tk.push_back(t1-t0); ta.push_back(t2-t1);
  }
  std::sort(tk.begin(),tk.end()); std::sort(ta.begin(),ta.end());
  printf("keep_largest_components %.1f ms, analyze_topology %.1f ms\n", tk[tk.size()/2]*1e3, ta[ta.size()/2]*1e3);
}
