#include "engine/format/motion.hpp"

#include "engine/util/byte_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace vkas::motion {

void srtToAffine(const double p[16], Affine3x4d& out) {
    const double sx = p[0], a = p[1], b = p[2], pvx = p[3], sy = p[4], c = p[5], pvy = p[6], sz = p[7], pvz = p[8];
    double qx = p[9], qy = p[10], qz = p[11], qw = p[12];
    const double tx = p[13], ty = p[14], tz = p[15];
    const double n = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
    if (n > 0.0 && std::isfinite(n)) {
        qx /= n, qy /= n, qz /= n, qw /= n;
    } else {  // no rotation can be derived: the identity
        qx = qy = qz = 0.0, qw = 1.0;
    }
    const double r[3][3] = {
        {1.0 - 2.0 * (qy * qy + qz * qz), 2.0 * (qx * qy - qz * qw), 2.0 * (qx * qz + qy * qw)},
        {2.0 * (qx * qy + qz * qw), 1.0 - 2.0 * (qx * qx + qz * qz), 2.0 * (qy * qz - qx * qw)},
        {2.0 * (qx * qz - qy * qw), 2.0 * (qy * qz + qx * qw), 1.0 - 2.0 * (qx * qx + qy * qy)},
    };
    // S = [[sx, a, b, pvx], [0, sy, c, pvy], [0, 0, sz, pvz]]; T * R * S = [R * S3 | R * pv + t].
    const double s[3][4] = {{sx, a, b, pvx}, {0.0, sy, c, pvy}, {0.0, 0.0, sz, pvz}};
    const double t[3] = {tx, ty, tz};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 4; ++j) {
            out.m[i][j] = r[i][0] * s[0][j] + r[i][1] * s[1][j] + r[i][2] * s[2][j];
            if (j == 3) out.m[i][j] += t[i];
        }
}

void transformAt(uint32_t type, const float motion[32], float time, Affine3x4d& out) {
    const double t1 = double(time), t0 = 1.0 - t1;
    if (type == kSrt) {
        double p[16];
        for (int k = 0; k < 16; ++k) p[k] = t0 * double(motion[k]) + t1 * double(motion[16 + k]);
        srtToAffine(p, out);
        return;
    }
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) out.m[r][c] = t0 * double(motion[4 * r + c]) + t1 * double(motion[12 + 4 * r + c]);
}

void instanceTransformsAt(const format::InstanceRecord& record, float time, float objectToWorld[3][4],
                          float worldToObject[3][4]) {
    if (record.motionType == kStatic) {
        std::memcpy(objectToWorld, record.objectToWorld, sizeof record.objectToWorld);
        std::memcpy(worldToObject, record.worldToObject, sizeof record.worldToObject);
        return;
    }
    const auto& rec = reinterpret_cast<const format::MotionInstanceRecord&>(record);
    Affine3x4d m;
    transformAt(record.motionType, rec.motion, time, m);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) objectToWorld[r][c] = float(m.m[r][c]);
    Affine3x4d inv;
    invertAffine(affineFromFloat(objectToWorld), inv);
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) worldToObject[r][c] = float(inv.m[r][c]);
}

namespace {

void extendByCorners(const Affine3x4d& m, const double boxLo[3], const double boxHi[3], double lo[3], double hi[3]) {
    for (int corner = 0; corner < 8; ++corner) {
        const double p[3] = {(corner & 1) ? boxHi[0] : boxLo[0], (corner & 2) ? boxHi[1] : boxLo[1],
                             (corner & 4) ? boxHi[2] : boxLo[2]};
        double q[3];
        applyAffine(m, p, q);
        for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], q[c]), hi[c] = std::max(hi[c], q[c]);
    }
}

}  // namespace

void instanceBounds(uint32_t type, const float staticTransform[3][4], const float motion[32], const double boxLo[3],
                    const double boxHi[3], double lo[3], double hi[3]) {
    for (int c = 0; c < 3; ++c) lo[c] = INFINITY, hi[c] = -INFINITY;
    if (type == kStatic) {
        extendByCorners(affineFromFloat(staticTransform), boxLo, boxHi, lo, hi);
        return;
    }
    const bool sameRotation = type == kSrt && std::memcmp(motion + 9, motion + 16 + 9, 4 * sizeof(float)) == 0;
    if (type == kMatrix || sameRotation) {
        // Every point moves affinely in time: the boxes at both ends hold the whole path.
        Affine3x4d m;
        transformAt(type, motion, 0.0f, m);
        extendByCorners(m, boxLo, boxHi, lo, hi);
        transformAt(type, motion, 1.0f, m);
        extendByCorners(m, boxLo, boxHi, lo, hi);
    } else {
        // p -> t(time) + R(time) (S(time) p): a rotation keeps |S p|, which is at most its largest value over the
        // box corners at time 0 or 1 (S(time) p is affine in time and in p, and a norm is convex).
        double radius = 0.0;
        for (int k = 0; k < 2; ++k) {
            const float* s = motion + 16 * k;
            for (int corner = 0; corner < 8; ++corner) {
                const double p[3] = {(corner & 1) ? boxHi[0] : boxLo[0], (corner & 2) ? boxHi[1] : boxLo[1],
                                     (corner & 4) ? boxHi[2] : boxLo[2]};
                const double x = double(s[0]) * p[0] + double(s[1]) * p[1] + double(s[2]) * p[2] + double(s[3]);
                const double y = double(s[4]) * p[1] + double(s[5]) * p[2] + double(s[6]);
                const double z = double(s[7]) * p[2] + double(s[8]);
                radius = std::max(radius, std::sqrt(x * x + y * y + z * z));
            }
        }
        radius *= 1.0 + 1e-12;  // the square root's rounding
        for (int c = 0; c < 3; ++c) {
            const double t0 = motion[13 + c], t1 = motion[16 + 13 + c];
            lo[c] = std::min(t0, t1) - radius;
            hi[c] = std::max(t0, t1) + radius;
        }
    }
    double scale = 0.0;
    for (int c = 0; c < 3; ++c) scale = std::max({scale, std::fabs(lo[c]), std::fabs(hi[c])});
    const double pad = std::ldexp(scale, -20);
    for (int c = 0; c < 3; ++c) lo[c] -= pad, hi[c] += pad;
}

}  // namespace vkas::motion
