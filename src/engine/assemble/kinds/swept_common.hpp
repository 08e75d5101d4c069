// [NV-LSS] What spheres (spheres.cpp) and linear swept spheres (lss.cpp) share: their input readers during an update
// and their boxes, the union of balls computed in double and rounded outwards.
#pragma once

#include <algorithm>
#include <optional>

#include "engine/assemble/refit.hpp"
#include "engine/input/build_inputs.hpp"
#include "engine/input/swept_spheres.hpp"
#include "engine/util/math.hpp"

namespace vkas {

// Grows [lo, hi] (double) by the ball (c, r).
inline void extendBall(double lo[3], double hi[3], const float c[3], float r) {
    for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], double(c[k]) - double(r));
        hi[k] = std::max(hi[k], double(c[k]) + double(r));
    }
}

// The float box that holds [lo, hi].
inline Aabb ballsBox(const double lo[3], const double hi[3]) {
    Aabb b;
    b.lower = {roundDown(lo[0]), roundDown(lo[1]), roundDown(lo[2])};
    b.upper = {roundUp(hi[0]), roundUp(hi[1]), roundUp(hi[2])};
    return b;
}

// The sphere or LSS reader of an update's geometries, one geometry at a time (as TriangleInputs in triangles.cpp).
class SweptInputs {
public:
    explicit SweptInputs(const RefitJob& job) : job_(job) {}
    const SweptSpheresSource* at(uint32_t g) {
        if (g >= job_.info->geometryCount) return nullptr;
        if (g != current_) {
            SweptSpheresData data;
            current_ = g;
            if (!sweptSpheresData(buildGeometry(*job_.info, g), data)) {
                source_.reset();
                return nullptr;
            }
            source_.emplace(data, job_.ranges[g]);
        }
        return source_ ? &*source_ : nullptr;
    }

private:
    const RefitJob& job_;
    std::optional<SweptSpheresSource> source_;
    uint32_t current_ = UINT32_MAX;
};

}  // namespace vkas
