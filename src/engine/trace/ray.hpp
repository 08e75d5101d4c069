// Ray set-up shared by every traversal path: the ray prepared once per structure it enters (inverse direction for
// the node test, the shear of the watertight triangle test) and the world-to-object transform of an instance.
#pragma once

#include <cmath>

namespace vkas {

struct ShearedRay {
    float org[3];
    float dir[3];
    float invDir[3];  // for box tests
    int kx, ky, kz;
    float sx, sy, sz;
};

// The axis of the largest direction component (|d| per axis), the watertight test's kz; ties go to the later axis
// of each comparison, as the shear has always chosen.
inline int dominantAxis(float ax, float ay, float az) { return (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2); }

inline void prepareShearedRay(ShearedRay& r, const float org[3], const float dir[3]) {
    for (int i = 0; i < 3; ++i) {
        r.org[i] = org[i];
        r.dir[i] = dir[i];
        r.invDir[i] = 1.0f / dir[i];
    }
    float ax = std::fabs(dir[0]), ay = std::fabs(dir[1]), az = std::fabs(dir[2]);
    r.kz = dominantAxis(ax, ay, az);
    r.kx = (r.kz + 1) % 3;
    r.ky = (r.kx + 1) % 3;
    if (dir[r.kz] < 0.0f) {  // keep the winding of the sheared triangle
        int t = r.kx;
        r.kx = r.ky;
        r.ky = t;
    }
    r.sx = dir[r.kx] / dir[r.kz];
    r.sy = dir[r.ky] / dir[r.kz];
    r.sz = 1.0f / dir[r.kz];
}

// The ray in an instance's object space: the 3x4 row-major world-to-object matrix applied in double, each result
// rounded once.
inline void transformRay(const float (*m)[4], const float o[3], const float d[3], float oo[3], float od[3]) {
    for (int r = 0; r < 3; ++r) {
        oo[r] = float(double(m[r][0]) * o[0] + double(m[r][1]) * o[1] + double(m[r][2]) * o[2] + double(m[r][3]));
        od[r] = float(double(m[r][0]) * d[0] + double(m[r][1]) * d[1] + double(m[r][2]) * d[2]);
    }
}

}  // namespace vkas
