#include "scene_writer.hpp"

#include <oracle.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace diff {

uint32_t vertexSize(VkFormat format) { return oracle::formatInfo(format).size; }
uint32_t componentSize(VkFormat format) { return oracle::formatInfo(format).componentSize; }

namespace {

template <typename T>
void put(uint8_t* out, T v) {
    std::memcpy(out, &v, sizeof v);
}

int64_t quantize(double v, double lo, double hi, double scale) {
    return std::llround(std::clamp(v, lo, hi) * scale);
}

}  // namespace

void encodeVertex(VkFormat format, const Point& p, uint8_t* out) {
    const oracle::FormatInfo& f = oracle::formatInfo(format);
    if (f.packed) {  // A2B10G10R10_UNORM_PACK32: R in bits 0-9, G 10-19, B 20-29, A 30-31
        uint32_t w = 0;
        for (int c = 0; c < 3; ++c) w |= uint32_t(quantize(p[c], 0.0, 1.0, 1023.0)) << (10 * c);
        put(out, w | (3u << 30));
        return;
    }
    for (uint32_t c = 0; c < f.components; ++c) {
        const double v = c < 3 ? p[c] : 1.0;
        uint8_t* dst = out + c * f.componentSize;
        if (f.isFloat) {
            if (f.componentSize == 8) put(dst, v);
            else if (f.componentSize == 4) put(dst, float(v));
            else put(dst, oracle::floatToHalf(float(v)));
        } else if (f.componentSize == 2) {
            put(dst, int16_t(quantize(v, -1.0, 1.0, 32767.0)));
        } else {
            put(dst, int8_t(quantize(v, -1.0, 1.0, 127.0)));
        }
    }
}

uint64_t SceneWriter::reserve(size_t size, size_t alignment) {
    auto& blob = scene_.blob;
    const size_t offset = (blob.size() + alignment - 1) / alignment * alignment;
    blob.resize(offset + size, 0xAA);
    return offset;
}

uint64_t SceneWriter::append(const void* data, size_t size, size_t alignment) {
    const uint64_t offset = reserve(size, alignment);
    if (size) std::memcpy(scene_.blob.data() + offset, data, size);
    return offset;
}

Geometry SceneWriter::triangles(const std::vector<Point>& positions, const std::vector<uint32_t>& indices,
                                const TriangleOptions& o) {
    const uint32_t triangleCount = uint32_t(indices.size() / 3);
    const uint32_t csize = componentSize(o.format);
    const uint64_t stride = vertexSize(o.format) + uint64_t(o.extraStride) * csize;
    const bool indexed = o.indexType != VK_INDEX_TYPE_NONE_KHR;

    Geometry g;
    g.type = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    g.flags = o.flags;
    g.range.primitiveCount = triangleCount;
    g.range.firstVertex = o.firstVertex;
    auto& t = g.triangles;
    t.vertexFormat = o.format;
    t.vertexStride = stride;
    t.indexType = o.indexType;

    // Vertex data: firstVertex vertices of garbage, then the vertices (unrolled when non-indexed). For non-indexed
    // geometry, primitiveOffset moves the vertex reads, so the garbage primitives go in front of the vertices too.
    const uint32_t vertexCount = indexed ? uint32_t(positions.size()) : 3 * triangleCount;
    const uint64_t skipBytes = indexed ? 0 : uint64_t(o.primitiveSkip) * 3 * stride;
    t.vertexOffset = reserve(size_t(skipBytes + (uint64_t(o.firstVertex) + vertexCount) * stride), 16);
    uint8_t* base = scene_.blob.data() + t.vertexOffset + skipBytes + uint64_t(o.firstVertex) * stride;
    for (uint32_t i = 0; i < vertexCount; ++i) {
        const Point& p = positions[indexed ? i : indices[i]];
        encodeVertex(o.format, p, base + i * stride);
    }
    // maxVertex counts firstVertex in (VUIDs 10774 / 10775); primitiveOffset moves the data instead.
    t.maxVertex = o.firstVertex + (vertexCount ? vertexCount - 1 : 0);
    if (indexed) {
        const uint32_t isize = o.indexType == VK_INDEX_TYPE_UINT16 ? 2 : 4;
        t.indexOffset = reserve((size_t(o.primitiveSkip) * 3 + indices.size()) * isize, 16);
        uint8_t* dst = scene_.blob.data() + t.indexOffset + size_t(o.primitiveSkip) * 3 * isize;
        for (size_t i = 0; i < indices.size(); ++i) {
            if (isize == 2) put(dst + 2 * i, uint16_t(indices[i]));
            else put(dst + 4 * i, indices[i]);
        }
        g.range.primitiveOffset = o.primitiveSkip * 3 * isize;
    } else {
        g.range.primitiveOffset = uint32_t(skipBytes);
    }
    if (o.transform) {
        t.hasTransform = true;
        t.transformOffset = reserve(size_t(o.transformSkip + 1) * sizeof(VkTransformMatrixKHR), 16);
        std::memcpy(scene_.blob.data() + t.transformOffset + o.transformSkip * sizeof(VkTransformMatrixKHR),
                    o.transform, sizeof(VkTransformMatrixKHR));
        g.range.transformOffset = o.transformSkip * uint32_t(sizeof(VkTransformMatrixKHR));
    }
    return g;
}

Geometry SceneWriter::aabbs(const std::vector<std::array<float, 6>>& boxes, const AabbOptions& o) {
    Geometry g;
    g.type = VK_GEOMETRY_TYPE_AABBS_KHR;
    g.flags = o.flags;
    g.aabbs.stride = 24 + 8 * uint64_t(o.extraStride);
    g.range.primitiveCount = uint32_t(boxes.size());
    g.range.primitiveOffset = uint32_t(o.primitiveSkip * g.aabbs.stride);
    g.aabbs.dataOffset = reserve(size_t((o.primitiveSkip + boxes.size()) * g.aabbs.stride), 16);
    uint8_t* dst = scene_.blob.data() + g.aabbs.dataOffset + g.range.primitiveOffset;
    for (size_t i = 0; i < boxes.size(); ++i) std::memcpy(dst + i * g.aabbs.stride, boxes[i].data(), 24);
    return g;
}

}  // namespace diff
