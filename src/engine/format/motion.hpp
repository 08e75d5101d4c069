// [NV-motion] VK_NV_ray_tracing_motion_blur: motion instances (static, matrix and SRT), their interpolation at a
// ray time, their bounds over the whole time range [0, 1]: how the format's motion records are read. The
// input side (the motion instance array, motion-triangle vertex data) is input/motion_inputs.hpp.
//
// Interpolation (spec: VkAccelerationStructureMatrixMotionInstanceNV / VkAccelerationStructureSRTMotionInstanceNV):
//   matrix motion: componentwise T0 * (1 - time) + T1 * time
//   SRT motion:    componentwise lerp of the 16 VkSRTDataNV parameters, then T * R * S, where S is the
//                  scale/shear/pivot matrix, R the rotation of the interpolated quaternion normalized (the spec
//                  leaves normalization open; a rotation needs a unit quaternion; a zero quaternion gives the
//                  identity rotation) and T the translation.
// Everything is computed in double and rounded once to float; the world-to-object transform is the double inverse
// of that float object-to-world transform, like the static instances' (so time 0 of a matrix motion instance with
// T0 == the static transform gives bit-identical results).
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cstdint>

#include "engine/format/layout.hpp"
#include "engine/util/math.hpp"

namespace vkas::motion {

constexpr uint32_t kStatic = VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_STATIC_NV;
constexpr uint32_t kMatrix = VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_MATRIX_MOTION_NV;
constexpr uint32_t kSrt = VK_ACCELERATION_STRUCTURE_MOTION_INSTANCE_TYPE_SRT_MOTION_NV;

constexpr bool isMotionBuild(VkBuildAccelerationStructureFlagsKHR flags) {
    return (flags & VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV) != 0;
}

// Linear interpolation of one coordinate, exact at time 0 and 1 and always between a and b.
inline float lerp(float a, float b, float time) {
    return float((1.0 - double(time)) * double(a) + double(time) * double(b));
}

// T * R * S of the 16 VkSRTDataNV parameters (sx, a, b, pvx, sy, c, pvy, sz, pvz, qx, qy, qz, qw, tx, ty, tz).
void srtToAffine(const double srt[16], Affine3x4d& out);
// The object-to-world transform of a matrix (kMatrix) or SRT (kSrt) motion at `time`, in double.
void transformAt(uint32_t type, const float motion[32], float time, Affine3x4d& out);
// The float object-to-world transform at `time` and its inverse (see above). Static records (motionType 0, every
// record of a non-motion structure) give their stored transforms.
void instanceTransformsAt(const format::InstanceRecord& record, float time, float objectToWorld[3][4],
                          float worldToObject[3][4]);

// A conservative world-space box of the object-space box [boxLo, boxHi] under the instance's transform over the
// whole time range [0, 1] (kStatic: `staticTransform`; otherwise `motion`). Matrix motion: each point moves on a
// segment, so the boxes at time 0 and 1 suffice. SRT motion with equal quaternions: the transform is affine in
// time, likewise. SRT motion with a changing rotation: the translation's segment grown by the largest length of
// S * p over the box corners and both times (a rotation keeps lengths, and |S(t) p| is convex in t). Matrix and SRT
// bounds are grown by 2^-20 of their magnitude for the rounding of the interpolated transforms.
void instanceBounds(uint32_t type, const float staticTransform[3][4], const float motion[32], const double boxLo[3],
                    const double boxHi[3], double lo[3], double hi[3]);

}  // namespace vkas::motion
