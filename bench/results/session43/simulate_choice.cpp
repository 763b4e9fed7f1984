// Replays Hybrid's choice of mode (src/cl/hybrid_schedule.hpp, as built) on the H200 machine's
// medians at 16 threads (forty-third session, h200/*_backends*.jsonl): per volume shape and type,
// the sphere, the gyroid and the CT phantom in turn, each a new volume; per volume an untimed
// set-up call, an untimed warm-up and 7 timed calls, as `voxmesh-bench --interleave --warmup 1
// --setup-first`. The CPU engine alone and the device alone take the CPU and OpenCL medians, the
// split 1.05x the CPU's; each call's time has lognormal noise. Ratio: the faster alone / the
// median of the 7 timed calls.
//   g++ -O2 -std=c++20 -I src bench/results/session43/simulate_choice.cpp -o /tmp/simulate_choice
//   /tmp/simulate_choice new [sigma]   (mesh sizes passed: the surface rule on)
//   /tmp/simulate_choice old [sigma]   (one size for every call: time ratios alone)
//   CELLS=1 ...                        (the first trial's cells and the modes each ran)
#include <cstdlib>
#include "cl/hybrid_schedule.hpp"
#include <cstdio>
#include <random>
#include <vector>
#include <string>
#include <algorithm>
#include <cmath>
using namespace voxmesh::detail;
struct Row { const char* type; int size; const char* field; double cpu, ocl, hyb; unsigned long tri; };
static const std::vector<std::vector<Row>> sets = {
// 04_785dc17_backends.jsonl
{
  {"f32",256,"sphere",2.11,3.62,2.33,395132},
  {"f32",512,"sphere",13.52,20.16,13.54,1581452},
  {"u8",256,"sphere",1.81,2.20,1.84,394748},
  {"u8",512,"sphere",9.33,9.66,9.22,1580396},
  {"f32",256,"gyroid",8.94,8.60,9.70,2513199},
  {"f32",512,"gyroid",48.86,42.19,41.71,10106415},
  {"u8",256,"gyroid",8.60,7.55,7.43,2513487},
  {"u8",512,"gyroid",38.84,31.49,29.94,10110063},
  {"f32",256,"ct",2.95,4.49,3.75,696828},
  {"f32",512,"ct",17.85,21.78,21.54,2785632},
  {"u8",256,"ct",2.50,2.53,2.58,696820},
  {"u8",512,"ct",13.05,11.02,11.14,2785632},
},
// 04_785dc17_backends_reuse.jsonl
{
  {"f32",256,"sphere",1.78,3.69,2.01,395132},
  {"f32",512,"sphere",11.97,19.09,13.56,1581452},
  {"u8",256,"sphere",1.36,2.02,1.48,394748},
  {"u8",512,"sphere",6.67,7.52,6.29,1580396},
  {"f32",256,"gyroid",5.50,5.25,5.21,2513199},
  {"f32",512,"gyroid",30.50,26.13,31.35,10106415},
  {"u8",256,"gyroid",4.35,3.64,3.47,2513487},
  {"u8",512,"gyroid",20.78,14.61,14.73,10110063},
  {"f32",256,"ct",2.13,3.69,2.18,696828},
  {"f32",512,"ct",13.84,18.59,15.28,2785632},
  {"u8",256,"ct",2.11,2.57,2.00,696820},
  {"u8",512,"ct",8.50,7.82,7.47,2785632},
},
// 01_9dd18b0_backends_reuse.jsonl
{
  {"f32",256,"sphere",1.93,3.23,2.20,395132},
  {"f32",512,"sphere",11.48,17.63,11.52,1581452},
  {"u8",256,"sphere",1.53,2.13,1.44,394748},
  {"u8",512,"sphere",6.30,8.55,6.44,1580396},
  {"f32",256,"gyroid",5.76,5.19,5.26,2513199},
  {"f32",512,"gyroid",33.45,23.90,23.72,10106415},
  {"u8",256,"gyroid",4.92,4.01,3.84,2513487},
  {"u8",512,"gyroid",24.90,13.31,13.79,10110063},
  {"f32",256,"ct",2.42,3.56,2.42,696828},
  {"f32",512,"ct",14.93,17.41,16.90,2785632},
  {"u8",256,"ct",2.20,2.27,2.26,696820},
  {"u8",512,"ct",9.75,7.18,6.93,2785632},
},
// 02_701da2e_backends_reuse.jsonl
{
  {"f32",256,"sphere",1.75,3.38,1.75,395132},
  {"f32",512,"sphere",11.65,18.90,11.86,1581452},
  {"u8",256,"sphere",1.43,2.01,1.40,394748},
  {"u8",512,"sphere",6.18,6.96,6.31,1580396},
  {"f32",256,"gyroid",5.44,4.95,4.85,2513199},
  {"f32",512,"gyroid",31.86,23.96,34.08,10106415},
  {"u8",256,"gyroid",4.57,4.01,3.71,2513487},
  {"u8",512,"gyroid",22.52,13.38,22.94,10110063},
  {"f32",256,"ct",2.14,3.47,2.22,696828},
  {"f32",512,"ct",13.36,17.36,15.97,2785632},
  {"u8",256,"ct",1.91,2.39,1.89,696820},
  {"u8",512,"ct",8.47,7.05,9.45,2785632},
},
// 01_9dd18b0_backends.jsonl
{
  {"f32",256,"sphere",1.93,3.47,1.91,395132},
  {"f32",512,"sphere",13.27,18.71,13.50,1581452},
  {"u8",256,"sphere",1.82,2.13,2.07,394748},
  {"u8",512,"sphere",9.37,10.02,10.00,1580396},
  {"f32",256,"gyroid",9.58,8.60,8.30,2513199},
  {"f32",512,"gyroid",49.44,41.12,40.47,10106415},
  {"u8",256,"gyroid",8.92,6.67,6.61,2513487},
  {"u8",512,"gyroid",41.13,30.64,30.86,10110063},
  {"f32",256,"ct",2.98,4.00,2.88,696828},
  {"f32",512,"ct",19.09,22.83,21.89,2785632},
  {"u8",256,"ct",2.72,2.62,2.63,696820},
  {"u8",512,"ct",14.58,11.92,11.53,2785632},
},
// 02_701da2e_backends.jsonl
{
  {"f32",256,"sphere",2.12,3.85,2.34,395132},
  {"f32",512,"sphere",14.02,20.71,13.67,1581452},
  {"u8",256,"sphere",1.59,2.14,1.62,394748},
  {"u8",512,"sphere",9.31,9.72,8.60,1580396},
  {"f32",256,"gyroid",10.27,9.64,10.36,2513199},
  {"f32",512,"gyroid",53.83,43.98,45.07,10106415},
  {"u8",256,"gyroid",9.13,7.96,8.45,2513487},
  {"u8",512,"gyroid",43.51,32.30,30.59,10110063},
  {"f32",256,"ct",2.70,4.06,2.68,696828},
  {"f32",512,"ct",19.01,21.84,21.84,2785632},
  {"u8",256,"ct",2.80,2.80,3.17,696820},
  {"u8",512,"ct",13.49,11.70,10.89,2785632},
},

};
static const char* names[] = {"04 fresh","04 reuse","01 reuse","02 reuse","01 fresh","02 fresh"};
int main(int argc, char** argv) {
    const bool surface_rule = argc > 1 && std::string(argv[1]) == "new";
    const double sigma = argc > 2 ? atof(argv[2]) : 0.08;
    std::mt19937 rng(7);
    std::lognormal_distribution<double> noise(0, sigma);
    for (size_t si = 0; si < sets.size(); ++si) {
        double logsum = 0; int n = 0, good = 0; double worst = 9;
        const int trials = 400;
        for (int trial = 0; trial < trials; ++trial) {
            HybridModeBook<std::pair<std::string,int>> book;
            std::vector<int> addr(sets[si].size());
            for (size_t i = 0; i < sets[si].size(); ++i) {
                const Row& r = sets[si][i];
                auto key = std::make_pair(std::string(r.type), r.size);
                const double base[3] = {1.05 * r.cpu, r.cpu, r.ocl};
                std::vector<double> timed; std::string ms;
                for (int call = 0; call < 9; ++call) {
                    HybridMode m = book.choose(key, &addr[i]);
                    double t = base[int(m)] * noise(rng); ms += "SCD"[int(m)];
                    book.record(key, &addr[i], m, t, surface_rule ? r.tri : 1);
                    if (call >= 2) timed.push_back(t);
                }
                std::sort(timed.begin(), timed.end());
                const double ratio = std::min(r.cpu, r.ocl) / timed[3];
                if (trial == 0 && getenv("CELLS")) { printf("  %s %s %d: ratio %.2f modes %s  (S %.1f C %.1f D %.1f)", r.field, r.type, r.size, ratio, ms.c_str(), base[0], base[1], base[2]); printf("\n"); }
                logsum += std::log(ratio); ++n; good += ratio >= 0.95; worst = std::min(worst, ratio);
            }
        }
        printf("%-9s %s: geomean %.3f, cells >= 0.95: %.1f%%, worst %.2f\n", names[si], surface_rule ? "new" : "old", std::exp(logsum / n), 100.0 * good / n, worst);
    }
}
