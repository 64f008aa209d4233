// Which hemicube faces a point can fall on: its outcode against the faces' planes (the worker's
// per-hemicube culling, gl/hemicube_worker.cpp). A bit set for every corner of a piece means the
// piece misses each face that has that plane.
#pragma once

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace ffcube {

// Bits 0..3: x > z, −x > z, y > z, −y > z (top face: |x|, |y| ≤ z); bit 4: z < 0; bits 5..8:
// y > x, −y > x, y > −x, −y > −x; bits 9..12: z > x, z > −x, z > y, z > −y (side faces). The
// comparisons as written, one by one (the reference for face_outcode).
inline unsigned face_outcode_scalar(float x, float y, float z) {
    const bool out[13] = {x > z, -x > z, y > z, -y > z, z < 0, y > x, -y > x, y > -x, -y > -x, z > x, z > -x, z > y, z > -y};
    unsigned code = 0;
    for (unsigned b = 0; b < 13; ++b) code |= static_cast<unsigned>(out[b]) << b;
    return code;
}

// The same bits, four comparisons at a time: the loop above compiled to a store and a load per
// bit, half of the culling's time on a city (docs/benchmarks.md, "Culling's outcodes").
inline unsigned face_outcode(float x, float y, float z) {
#if defined(__SSE2__)
    const __m128 a = _mm_set_ps(-y, y, -x, x);  // lanes 0..3: x, −x, y, −y
    const __m128 zz = _mm_set1_ps(z);
    const __m128 b = _mm_set_ps(-y, y, -y, y);  // y, −y, y, −y
    const __m128 c = _mm_set_ps(-x, -x, x, x);  // x, x, −x, −x
    const auto top = static_cast<unsigned>(_mm_movemask_ps(_mm_cmpgt_ps(a, zz)));
    const auto diag = static_cast<unsigned>(_mm_movemask_ps(_mm_cmpgt_ps(b, c)));
    const auto side = static_cast<unsigned>(_mm_movemask_ps(_mm_cmpgt_ps(zz, a)));
    return top | (static_cast<unsigned>(z < 0) << 4) | (diag << 5) | (side << 9);
#else
    return face_outcode_scalar(x, y, z);
#endif
}

}  // namespace ffcube
