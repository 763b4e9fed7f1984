#include "normal_batch.hpp"

#include "edge_vertex.hpp"
#include "row_packer.hpp"  // cpu_has_avx2_bmi2

#include <cfloat>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define VOXMESH_NORMALS_AVX 1
#endif

namespace voxmesh::detail {

namespace {

void normalise_one(const double* x, const double* y, const double* z, const std::uint8_t* flat, std::size_t v,
                   float* out) {
    const double n[3] = {x[v], y[v], z[v]};
    normalise_normal(n, flat[v], out + 3 * v);
}

#ifdef VOXMESH_NORMALS_AVX
// Four normals a step, as many whole steps as count holds; returns how many it normalised.
// len2 = x*x + y*y + z*z in that order, 1 / sqrt(len2), products rounded to float (IEEE
// square root and divide round exactly, no fused multiply-adds: the scalar bits). Lanes
// whose len2 is not a normal finite number are redone by the scalar code (its scaled path).
[[gnu::target("avx2")]] std::size_t normalise_avx(const double* x, const double* y, const double* z,
                                                  const std::uint8_t* flat, std::size_t count, float* out) {
    const __m256d one = _mm256_set1_pd(1.0), min = _mm256_set1_pd(DBL_MIN), max = _mm256_set1_pd(DBL_MAX);
    std::size_t v = 0;
    for (; v + 4 <= count; v += 4) {
        const __m256d nx = _mm256_loadu_pd(x + v), ny = _mm256_loadu_pd(y + v), nz = _mm256_loadu_pd(z + v);
        const __m256d len2 =
            _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(nx, nx), _mm256_mul_pd(ny, ny)), _mm256_mul_pd(nz, nz));
        const __m256d inv = _mm256_div_pd(one, _mm256_sqrt_pd(len2));
        alignas(16) float lane[3][4];
        _mm_store_ps(lane[0], _mm256_cvtpd_ps(_mm256_mul_pd(nx, inv)));
        _mm_store_ps(lane[1], _mm256_cvtpd_ps(_mm256_mul_pd(ny, inv)));
        _mm_store_ps(lane[2], _mm256_cvtpd_ps(_mm256_mul_pd(nz, inv)));
        float* o = out + 3 * v;
        for (unsigned l = 0; l < 4; ++l)
            for (unsigned d = 0; d < 3; ++d) o[3 * l + d] = lane[d][l];
        // Ordered compares: false for NaN, so a NaN len2 is redone as well.
        const __m256d ok = _mm256_and_pd(_mm256_cmp_pd(len2, min, _CMP_GE_OQ), _mm256_cmp_pd(len2, max, _CMP_LE_OQ));
        const int bad = ~_mm256_movemask_pd(ok) & 15;
        if (bad)
            for (unsigned l = 0; l < 4; ++l)
                if (bad >> l & 1) normalise_one(x, y, z, flat, v + l, out);
    }
    return v;
}
#endif

}  // namespace

void normalise_normals(const double* x, const double* y, const double* z, const std::uint8_t* flat,
                       std::size_t count, float* out) {
    std::size_t v = 0;
#ifdef VOXMESH_NORMALS_AVX
    static const bool avx = cpu_has_avx2_bmi2();
    if (avx) v = normalise_avx(x, y, z, flat, count, out);
#endif
    for (; v < count; ++v) normalise_one(x, y, z, flat, v, out);
}

}  // namespace voxmesh::detail
