// Reads build inputs exactly as VkAccelerationStructureBuildRangeInfoKHR defines: which bytes hold triangle i's
// vertices, its transform, AABB i, and which instance is number i. Host pointers have no alignment requirement.
#pragma once

#include <vulkan/vulkan_core.h>

#include <cstddef>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "engine/util/math.hpp"
#include "engine/input/vertex_format.hpp"

namespace vkas {

// How a triangle geometry's inputs are read, decided once per geometry so that the per-triangle loops of builds
// and refits run without a switch per vertex (TriangleSource::visit).
enum class TriangleIndexKind : uint8_t { None, U16, U32 };
// Float3: R32G32B32_SFLOAT or R32G32B32A32_SFLOAT (the 4th component is ignored); Float2: R32G32_SFLOAT (z = 0);
// Other: every other format, through decodeVertex.
enum class TriangleVertexKind : uint8_t { Float3, Float2, Other };

// The float a float vertex component becomes after the double round trip of the general decode (float -> double
// -> float): itself, except that a signalling NaN comes back quiet (x86 conversions keep the payload and set the
// quiet bit).
inline float roundTripFloat(float x) {
    uint32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    if ((bits & 0x7FFF'FFFFu) > 0x7F80'0000u) bits |= 0x0040'0000u;
    std::memcpy(&x, &bits, sizeof x);
    return x;
}

class TriangleSource {
public:
    TriangleSource(const VkAccelerationStructureGeometryTrianglesDataKHR& data,
                   const VkAccelerationStructureBuildRangeInfoKHR& range);

    uint32_t primitiveCount() const { return count_; }
    // Object-space positions of triangle i (after decode and geometry transform). Returns false when the
    // triangle is inactive (the X of a vertex is NaN in the input data).
    bool fetch(uint32_t i, float v[3][3]) const;
    // The vertex index (before firstVertex is added) that corner j of triangle i reads.
    uint64_t vertexIndex(uint32_t i, uint32_t j) const;

    TriangleIndexKind indexKind() const { return indexKind_; }
    TriangleVertexKind vertexKind() const { return vertexKind_; }
    bool hasTransform() const { return hasTransform_; }

    // fetch() for a geometry of the given kinds (which must be this source's): the same values, with the
    // dispatch resolved at compile time.
    template <TriangleIndexKind I, TriangleVertexKind V, bool T>
    bool fetchAs(uint32_t i, float v[3][3]) const;
    template <TriangleIndexKind I>
    uint64_t vertexIndexAs(uint32_t i, uint32_t j) const {
        const uint64_t k = 3ull * i + j;
        if constexpr (I == TriangleIndexKind::U16) return loadUnaligned<uint16_t>(indices_ + 2 * k);
        else if constexpr (I == TriangleIndexKind::U32) return loadUnaligned<uint32_t>(indices_ + 4 * k);
        else return k;
    }
    // Where triangle i's three indices are (null without an index buffer): for prefetching.
    template <TriangleIndexKind I>
    const std::byte* indexPointer(uint32_t i) const {
        if constexpr (I == TriangleIndexKind::U16) return indices_ + 6ull * i;
        else if constexpr (I == TriangleIndexKind::U32) return indices_ + 12ull * i;
        else return nullptr;
    }
    // The first byte of corner j of triangle i.
    template <TriangleIndexKind I>
    const std::byte* vertexPointer(uint32_t i, uint32_t j) const {
        return vertices_ + stride_ * vertexIndexAs<I>(i, j);
    }

    // Calls f(Reader) once, with Reader a TriangleReader of this source's kinds: loops written inside f fetch
    // without per-vertex dispatch. Returns what f returns.
    template <class F>
    decltype(auto) visit(F&& f) const;

private:
    VkFormat format_;
    const std::byte* vertices_;  // first vertex the geometry may address (firstVertex already applied)
    uint64_t stride_;
    VkIndexType indexType_;
    const std::byte* indices_;  // indexData + primitiveOffset
    bool hasTransform_;
    TriangleIndexKind indexKind_;
    TriangleVertexKind vertexKind_;
    Affine3x4d transform_;
    uint32_t count_;
};

// A TriangleSource with its kinds fixed at compile time (TriangleSource::visit).
template <TriangleIndexKind I, TriangleVertexKind V, bool T>
struct TriangleReader {
    static constexpr TriangleIndexKind kIndex = I;
    static constexpr TriangleVertexKind kVertex = V;
    static constexpr bool kTransform = T;
    const TriangleSource* source;
    uint32_t primitiveCount() const { return source->primitiveCount(); }
    bool fetch(uint32_t i, float v[3][3]) const { return source->fetchAs<I, V, T>(i, v); }
    const std::byte* vertexPointer(uint32_t i, uint32_t j) const { return source->vertexPointer<I>(i, j); }
    const std::byte* indexPointer(uint32_t i) const { return source->indexPointer<I>(i); }
};

template <TriangleIndexKind I, TriangleVertexKind V, bool T>
inline bool TriangleSource::fetchAs(uint32_t i, float v[3][3]) const {
    bool active = true;
    for (uint32_t j = 0; j < 3; ++j) {
        const std::byte* p = vertexPointer<I>(i, j);
        if constexpr (V != TriangleVertexKind::Other && !T) {
            // No transform: the general decode's double round trip is the identity but for NaN quieting.
            const float x = loadUnaligned<float>(p), y = loadUnaligned<float>(p + 4);
            if (std::isnan(x)) active = false;  // inactive: any NaN in a vertex's raw X
            v[j][0] = roundTripFloat(x);
            v[j][1] = roundTripFloat(y);
            v[j][2] = V == TriangleVertexKind::Float3 ? roundTripFloat(loadUnaligned<float>(p + 8)) : 0.0f;
        } else {
            double d[3];
            if constexpr (V == TriangleVertexKind::Float3) {
                for (int c = 0; c < 3; ++c) d[c] = loadUnaligned<float>(p + 4 * c);
            } else if constexpr (V == TriangleVertexKind::Float2) {
                d[0] = loadUnaligned<float>(p), d[1] = loadUnaligned<float>(p + 4), d[2] = 0.0;
            } else {
                decodeVertex(format_, p, d);
            }
            if (std::isnan(d[0])) active = false;  // inactive: any NaN in a vertex's raw X
            if constexpr (T) {
                double q[3];
                applyAffine(transform_, d, q);
                for (int c = 0; c < 3; ++c) v[j][c] = float(q[c]);
            } else {
                for (int c = 0; c < 3; ++c) v[j][c] = float(d[c]);
            }
        }
    }
    return active;
}

template <class F>
decltype(auto) TriangleSource::visit(F&& f) const {
    using IK = TriangleIndexKind;
    using VK = TriangleVertexKind;
    auto withVertex = [&]<IK I>() -> decltype(auto) {
        auto withTransform = [&]<VK V>() -> decltype(auto) {
            if (hasTransform_) return f(TriangleReader<I, V, true>{this});
            return f(TriangleReader<I, V, false>{this});
        };
        switch (vertexKind_) {
            case VK::Float3: return withTransform.template operator()<VK::Float3>();
            case VK::Float2: return withTransform.template operator()<VK::Float2>();
            default: return withTransform.template operator()<VK::Other>();
        }
    };
    switch (indexKind_) {
        case IK::U16: return withVertex.template operator()<IK::U16>();
        case IK::U32: return withVertex.template operator()<IK::U32>();
        default: return withVertex.template operator()<IK::None>();
    }
}

}  // namespace vkas
