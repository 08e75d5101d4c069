#include "oracle_micromap.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <stdexcept>

namespace oracle {

namespace {

std::mutex registryMutex;
std::map<uint64_t, std::shared_ptr<const Micromap>>& registry() {
    static std::map<uint64_t, std::shared_ptr<const Micromap>> r;
    return r;
}

template <class T>
T loadAt(const uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

}  // namespace

std::shared_ptr<const Micromap> decodeMicromap(const VkMicromapBuildInfoEXT& info, uint32_t triangleCount) {
    auto m = std::make_shared<Micromap>();
    const auto* tris = static_cast<const uint8_t*>(info.triangleArray.hostAddress);
    const auto* data = static_cast<const uint8_t*>(info.data.hostAddress);
    for (uint32_t i = 0; i < triangleCount; ++i) {
        // "laid out as a 4 byte unsigned integer for the dataOffset followed by a 2 byte unsigned integer for the
        // subdivision level then a 2 byte unsigned integer for the format"
        const uint8_t* e = tris + uint64_t(i) * info.triangleArrayStride;
        MicromapTriangle t;
        const uint32_t offset = loadAt<uint32_t>(e);
        t.level = loadAt<uint16_t>(e + 4);
        t.format = loadAt<uint16_t>(e + 6);
        const uint64_t count = uint64_t(1) << (2 * t.level);
        const uint32_t bits = t.format == VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT ? 1 : 2;
        t.states.resize(count);
        // "packed as either one bit per element [...] or two bits per element [...] and is packed from LSB to MSB in
        // each byte"
        for (uint64_t k = 0; k < count; ++k) {
            const uint64_t bit = k * bits;
            t.states[k] = uint8_t((data[offset + bit / 8] >> (bit % 8)) & ((1u << bits) - 1));
        }
        m->triangles.push_back(std::move(t));
    }
    return m;
}

void registerMicromap(VkMicromapEXT handle, std::shared_ptr<const Micromap> micromap) {
    std::lock_guard<std::mutex> lock(registryMutex);
    registry()[uint64_t(handle)] = std::move(micromap);
}
void forgetMicromaps() {
    std::lock_guard<std::mutex> lock(registryMutex);
    registry().clear();
}

std::shared_ptr<const GeometryMicromap> fetchGeometryMicromap(const VkAccelerationStructureGeometryTrianglesDataKHR& t,
                                                             uint32_t primitiveCount) {
    const VkAccelerationStructureTrianglesOpacityMicromapEXT* omm = nullptr;
    for (auto* p = static_cast<const VkBaseInStructure*>(t.pNext); p; p = p->pNext)
        if (p->sType == VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_TRIANGLES_OPACITY_MICROMAP_EXT)
            omm = reinterpret_cast<const VkAccelerationStructureTrianglesOpacityMicromapEXT*>(p);
    if (!omm) return nullptr;
    auto g = std::make_shared<GeometryMicromap>();
    if (omm->micromap != VK_NULL_HANDLE) {
        std::lock_guard<std::mutex> lock(registryMutex);
        auto it = registry().find(uint64_t(omm->micromap));
        // A micromap the test did not register (the valid-usage cases, which never trace): no micromap to read.
        if (it == registry().end()) return nullptr;
        g->micromap = it->second;
    }
    const auto* base = static_cast<const uint8_t*>(omm->indexBuffer.hostAddress);
    for (uint32_t i = 0; i < primitiveCount; ++i) {
        // "If indexType is VK_INDEX_TYPE_NONE_KHR, then the index used is the index of the triangle in the geometry."
        // "If that value is the unsigned cast of one of the values from VkOpacityMicromapSpecialIndexEXT then that
        // triangle behaves as described for that special value"; "Otherwise that triangle uses the opacity micromap
        // information from micromap at that index plus baseTriangle."
        int64_t ref;
        if (omm->indexType == VK_INDEX_TYPE_UINT16) {
            const uint16_t x = loadAt<uint16_t>(base + uint64_t(i) * omm->indexStride);
            ref = x >= uint16_t(-4) ? int64_t(int16_t(x)) : int64_t(x) + omm->baseTriangle;
        } else if (omm->indexType == VK_INDEX_TYPE_UINT32) {
            const uint32_t x = loadAt<uint32_t>(base + uint64_t(i) * omm->indexStride);
            ref = x >= uint32_t(-4) ? int64_t(int32_t(x)) : int64_t(x) + omm->baseTriangle;
        } else {
            ref = int64_t(i) + omm->baseTriangle;
        }
        g->reference.push_back(ref);
    }
    return g;
}

uint32_t microTriangleOf(double u, double v, uint32_t level, double* margin) {
    // The point's weights (w0, w1, w2) against the current triangle, whose corners play the roles of vertices 0, 1
    // and 2 in the order the curve gives them. The four children: nearest corner 0, the middle one, nearest corner 1,
    // nearest corner 2; the middle and the corner-2 child traverse with their first two corners swapped ("ordering
    // flipped"). Halving is exact in double for the barycentrics of a float hit, so the descent is exact.
    double w[3] = {1.0 - u - v, u, v};
    double nearest = INFINITY;
    uint32_t index = 0;
    for (uint32_t l = 0; l < level; ++l) {
        const double scale = std::ldexp(1.0, -int(l) - 1);  // one weight unit here, in the root's units: 2^-l, halved
        // Distance to the three midlines (w_k = 1/2) inside this triangle, in root barycentric units.
        for (int k = 0; k < 3; ++k) nearest = std::min(nearest, std::fabs(w[k] - 0.5) * 2.0 * scale);
        uint32_t child;
        double c[3];
        if (w[0] >= 0.5) {  // corner 0: corners (0, m01, m02)
            child = 0, c[0] = 2 * w[0] - 1, c[1] = 2 * w[1], c[2] = 2 * w[2];
        } else if (w[1] >= 0.5) {  // corner 1: (m01, 1, m12)
            child = 2, c[0] = 2 * w[0], c[1] = 2 * w[1] - 1, c[2] = 2 * w[2];
        } else if (w[2] >= 0.5) {  // corner 2, flipped: (m12, m02, 2)
            child = 3, c[0] = 2 * w[1], c[1] = 2 * w[0], c[2] = 2 * w[2] - 1;
        } else {  // the middle, flipped: (m02, m12, m01)
            child = 1, c[0] = 1 - 2 * w[1], c[1] = 1 - 2 * w[0], c[2] = 1 - 2 * w[2];
        }
        index = index * 4 + child;
        for (int k = 0; k < 3; ++k) w[k] = c[k];
    }
    if (margin) *margin = nearest;
    return index;
}

Opacity opacityOfState(uint32_t state, bool force2State) {
    switch (state) {
        case 0: return Opacity::Ignored;
        case 1: return Opacity::Opaque;
        case 2: return force2State ? Opacity::Ignored : Opacity::NonOpaque;
        default: return force2State ? Opacity::Opaque : Opacity::NonOpaque;
    }
}

std::vector<Opacity> micromapOutcomes(const GeometryMicromap& m, size_t primitive, double u, double v, double tolerance,
                                      bool force2State) {
    const int64_t ref = m.reference.at(primitive);
    if (ref < 0) return {opacityOfState(uint32_t(-1 - ref), force2State)};  // -1 .. -4: the special rows
    const MicromapTriangle& t = m.micromap->triangles.at(size_t(ref));
    // The spec's reference code clamps the barycentrics to [0, 1] first.
    auto clamp01 = [](double x) { return std::min(1.0, std::max(0.0, x)); };
    double margin;
    const uint32_t at = microTriangleOf(clamp01(u), clamp01(v), t.level, &margin);
    std::vector<Opacity> out{opacityOfState(t.states[at], force2State)};
    if (margin > 2 * tolerance) return out;
    // Near a micro-edge: every micro-triangle within the tolerance (sampled densely around the point).
    const int kSteps = 4;
    for (int i = -kSteps; i <= kSteps; ++i)
        for (int j = -kSteps; j <= kSteps; ++j) {
            const double du = u + 2 * tolerance * i / kSteps, dv = v + 2 * tolerance * j / kSteps;
            const Opacity o = opacityOfState(t.states[microTriangleOf(clamp01(du), clamp01(dv), t.level)], force2State);
            if (std::find(out.begin(), out.end(), o) == out.end()) out.push_back(o);
        }
    return out;
}

}  // namespace oracle
