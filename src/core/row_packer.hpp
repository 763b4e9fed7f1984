// Packing one row of samples into inside bits (value >= threshold), 64 to a word: the
// step that reads every sample, so it has an AVX2 variant chosen at run time. Both variants
// give identical bits; bits past the row's end are 0.
#pragma once

#include <cstddef>
#include <cstdint>

// Where AVX2 copies of a loop can be compiled beside the baseline and chosen at run time.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define VOXMESH_X86_DISPATCH 1
#endif

namespace voxmesh::detail {

using Word = std::uint64_t;

// Writes words_per_row(nx) words; returns true when the row holds a NaN or an infinity.
template <class T>
using RowPacker = bool (*)(const T* values, std::size_t nx, T threshold, Word* out);

template <class T>
bool pack_row_portable(const T* values, std::size_t nx, T threshold, Word* out);

// Null where the build or the processor has no AVX2.
template <class T>
RowPacker<T> avx2_row_packer();

// The fastest packer this processor runs; the environment variable VOXMESH_ISA=portable (or
// popcnt) forces the portable one (to compare, or to rule the vector code out).
template <class T>
RowPacker<T> row_packer();

// True when the processor has AVX2 and VOXMESH_ISA does not limit it: other AVX2 copies
// (value_range's) follow the packers' choice, so that the portable run tests them too.
bool use_avx2();

// True when the processor has POPCNT (and the build may use it), unless VOXMESH_ISA=portable:
// see cpu_engine.cpp.
bool cpu_has_popcnt();

// True when the processor has POPCNT, AVX2, BMI1 and BMI2 (and the build may use them): the
// generator has a copy compiled for them (cpu_engine.cpp). VOXMESH_ISA=portable or popcnt turns
// it off too.
bool cpu_has_avx2_bmi2();

}  // namespace voxmesh::detail
