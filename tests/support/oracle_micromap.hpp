// [EXT-OMM] The oracle's opacity micromaps, written from the specification's text alone (never from vkas's code or
// blocks): the micromap as the application gave it to vkBuildMicromapsEXT (formats, levels and states decoded from
// its triangleArray and data), which micromap triangle each triangle of a geometry uses (its
// VkAccelerationStructureTrianglesOpacityMicromapEXT, read again here), the micro-triangle a point selects by a
// recursive descent in double precision ("traversing into the sub-triangle nearest vertex 0, then the middle
// triangle with ordering flipped, then nearest vertex 1, then nearest vertex 2 with ordering flipped"), and the
// opacity tables of "Ray Opacity Micromap".
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace oracle {

struct MicromapTriangle {
    uint32_t format = 0;  // VkOpacityMicromapFormatEXT
    uint32_t level = 0;
    std::vector<uint8_t> states;  // one per micro-triangle, in the curve's order
};
struct Micromap {
    std::vector<MicromapTriangle> triangles;
};
// Decodes what vkBuildMicromapsEXT is given: triangleCount entries of triangleArray, the states from data.
std::shared_ptr<const Micromap> decodeMicromap(const VkMicromapBuildInfoEXT& info, uint32_t triangleCount);

// The micromaps the tests built, by VkMicromapEXT handle, for fetchTriangles to find.
void registerMicromap(VkMicromapEXT handle, std::shared_ptr<const Micromap> micromap);
void forgetMicromaps();

// A geometry's use of its micromap: per triangle, a micromap triangle index (>= 0) or a special index (-1 .. -4).
struct GeometryMicromap {
    std::vector<int64_t> reference;
    std::shared_ptr<const Micromap> micromap;  // null for VK_NULL_HANDLE
};
// The geometry's micromap, or null when its triangles have none.
std::shared_ptr<const GeometryMicromap> fetchGeometryMicromap(const VkAccelerationStructureGeometryTrianglesDataKHR& t,
                                                             uint32_t primitiveCount);

// Micro-triangle index (position along the curve) of the point with weights u (vertex 1) and v (vertex 2), at
// `level`, by recursive descent. `margin` receives the distance, in barycentric units, from the point to the
// nearest edge between two micro-triangles (how far it may move and still select the same one).
uint32_t microTriangleOf(double u, double v, uint32_t level, double* margin = nullptr);

enum class Opacity { Ignored, Opaque, NonOpaque };
// The state's meaning: the first table, or with force2State the 2-state override's.
Opacity opacityOfState(uint32_t state, bool force2State);

// What triangle `primitive` of a geometry with micromap `m` resolves to at (u, v) when the implementation's
// barycentrics may be off by `tolerance`: every outcome it can have (one unless the point is that close to a
// micro-edge whose sides differ).
std::vector<Opacity> micromapOutcomes(const GeometryMicromap& m, size_t primitive, double u, double v, double tolerance,
                                      bool force2State);

}  // namespace oracle
