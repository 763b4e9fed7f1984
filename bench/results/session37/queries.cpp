// The thirty-seventh session's timing of the query vector forms (bench/NOTES.md): per round
// vertex_edges, triangle_cells, edge_cell_ranges (over one list of edges made first) and
// extract, 2 threads, medians of 15 rounds. Built against two builds' static libraries, e.g.
//   g++ -O2 -std=c++20 -Iinclude -Ibuild/include bench/results/session37/queries.cpp \
//       build/src/libvoxmesh.a -lOpenCL -lz -lpthread -o /tmp/q_new
// and run in turn: /tmp/q_old gyroid 512; /tmp/q_new gyroid 512; ... (queries.txt).
#include <voxmesh/voxmesh.hpp>
#include <voxmesh/fields.hpp>
#include <chrono>
#include <cstdio>
#include <algorithm>
#include <vector>
static double now(){return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();}
int main(int argc,char**argv){
  const char* field=argc>1?argv[1]:"gyroid"; size_t n=argc>2?atoi(argv[2]):512;
  auto f=voxmesh::make_field(voxmesh::parse_field(field),n,voxmesh::ScalarType::U8,1);
  auto view=f.volume.view();
  std::vector<double> te,tc,tr,tx;
  size_t ne=0,nc=0;
  auto e0=voxmesh::vertex_edges(view,f.iso,2);
  for(int r=0;r<15;++r){
    double t0=now(); auto e=voxmesh::vertex_edges(view,f.iso,2); double t1=now();
    auto c=voxmesh::triangle_cells(view,f.iso,2); double t2=now();
    auto g=voxmesh::edge_cell_ranges(view,e0,f.iso,nullptr,2); double t3=now();
    voxmesh::Options o; o.iso=f.iso; o.threads=2; auto m=voxmesh::extract(view,o); double t4=now();
    te.push_back(t1-t0); tc.push_back(t2-t1); tr.push_back(t3-t2); tx.push_back(t4-t3); ne=e.size(); nc=c.size();
  }
  auto med=[](std::vector<double> v){std::sort(v.begin(),v.end());return v[v.size()/2]*1e3;};
  printf("%s u8 %zu: vertex_edges %.1f ms (%zu), triangle_cells %.1f ms (%zu), edge_cell_ranges %.1f ms, extract %.1f ms\n",field,n,med(te),ne,med(tc),nc,med(tr),med(tx));
}
