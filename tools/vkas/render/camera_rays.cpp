#include "camera_rays.hpp"

#include <cmath>
#include <numbers>

namespace vkas_tool {

std::vector<VkasRay> primaryRays(const Camera& cam, uint32_t W, uint32_t H, float tMax) {
    const Vec3 forward = normalize(cam.target - cam.position);
    const Vec3 right = normalize(cross(forward, cam.up));
    const Vec3 up = cross(right, forward);
    const float tanHalf = std::tan(cam.verticalFovDegrees * std::numbers::pi_v<float> / 360.0f);
    const float aspect = static_cast<float>(W) / static_cast<float>(H);
    std::vector<VkasRay> rays(static_cast<size_t>(W) * H);
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const float sx = (2.0f * (x + 0.5f) / W - 1.0f) * tanHalf * aspect;
            const float sy = (1.0f - 2.0f * (y + 0.5f) / H) * tanHalf;
            VkasRay& r = rays[static_cast<size_t>(y) * W + x];
            const Vec3 d = normalize(forward + right * sx + up * sy);
            r.origin[0] = cam.position.x, r.origin[1] = cam.position.y, r.origin[2] = cam.position.z;
            r.direction[0] = d.x, r.direction[1] = d.y, r.direction[2] = d.z;
            r.tMin = 0.0f;
            r.tMax = tMax;
        }
    }
    return rays;
}

}  // namespace vkas_tool
