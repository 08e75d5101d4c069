// libFuzzer target: decodes the input (build_spec.hpp) into build parameters of every geometry type and calls
// vkGetAccelerationStructureBuildSizesKHR and vkBuildAccelerationStructuresKHR with validation on. The contract
// checked (docs/API.md, section 8):
//   - a call validation reports nothing for must succeed (deferred: complete with VK_SUCCESS);
//   - a call it reports must return VK_ERROR_VALIDATION_FAILED_EXT and leave the destination, source and scratch
//     memory (poisoned with 0xAA) byte-identical;
//   - inputs are never written; a build writes nothing of its buffer outside [offset, offset + usedSize);
//   - what a build wrote is accepted by serialization, loads back identically, and traces.
// Every host pointer points into memory the harness owns, sized for everything the decoded parameters let a
// correct implementation read (the application's side of the contract, which vkas cannot check), and allocated
// with its exact size so that AddressSanitizer reports any read past it.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <memory>
#include <vector>

#include "build_spec.hpp"
#include "fuzz_common.hpp"

namespace {

using fz::Buffer;
using fz::BuildSpec;
using fz::Device;
using fz::GeomSpec;
using fz::Region;
using fz::Structure;

struct FormatInfo {
    VkFormat format;
    uint32_t size;       // bytes of one vertex (unsupported formats: the largest, 32)
    bool float32;        // 32-bit float components
};
constexpr FormatInfo kFormats[] = {
    {VK_FORMAT_R32G32B32_SFLOAT, 12, true},       {VK_FORMAT_R32G32_SFLOAT, 8, true},
    {VK_FORMAT_R32G32B32A32_SFLOAT, 16, true},    {VK_FORMAT_R16G16_SFLOAT, 4, false},
    {VK_FORMAT_R16G16B16_SFLOAT, 6, false},       {VK_FORMAT_R16G16B16A16_SFLOAT, 8, false},
    {VK_FORMAT_R16G16_SNORM, 4, false},           {VK_FORMAT_R16G16B16_SNORM, 6, false},
    {VK_FORMAT_R16G16B16A16_SNORM, 8, false},     {VK_FORMAT_R8G8_SNORM, 2, false},
    {VK_FORMAT_R8G8B8_SNORM, 3, false},           {VK_FORMAT_R8G8B8A8_SNORM, 4, false},
    {VK_FORMAT_R64G64_SFLOAT, 16, false},         {VK_FORMAT_R64G64B64_SFLOAT, 24, false},
    {VK_FORMAT_R64G64B64A64_SFLOAT, 32, false},   {VK_FORMAT_A2B10G10R10_UNORM_PACK32, 4, false},
    {VK_FORMAT_UNDEFINED, 32, false},             {VK_FORMAT_R32_SFLOAT, 32, false},
    {VK_FORMAT_R8G8B8A8_UNORM, 32, false},        {VkFormat(0x7FFFFFF0), 32, false},
};
constexpr uint32_t kFormatCount = sizeof(kFormats) / sizeof(kFormats[0]);
constexpr VkIndexType kIndexTypes[4] = {VK_INDEX_TYPE_NONE_KHR, VK_INDEX_TYPE_UINT16, VK_INDEX_TYPE_UINT32,
                                        VkIndexType(5)};
constexpr VkGeometryTypeKHR kGeometryTypes[5] = {VK_GEOMETRY_TYPE_TRIANGLES_KHR, VK_GEOMETRY_TYPE_AABBS_KHR,
                                                 VK_GEOMETRY_TYPE_INSTANCES_KHR, VK_GEOMETRY_TYPE_SPHERES_NV,
                                                 VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV};

uint32_t indexSize(VkIndexType t) { return t == VK_INDEX_TYPE_UINT16 ? 2 : 4; }

// The payload: bytes that fill the data regions, cycled.
class Payload {
public:
    Payload(const uint8_t* data, size_t size) : data_(data), size_(size) {}
    void fill(uint8_t* out, size_t n) {
        if (size_ == 0) {
            std::memset(out, 0x3F, n);
            return;
        }
        // out[i] = data_[(pos_ + i) % size_], copied in runs (a byte loop costs much under coverage instrumentation).
        for (size_t done = 0; done < n;) {
            const size_t run = std::min(n - done, size_ - pos_);
            std::memcpy(out + done, data_ + pos_, run);
            done += run;
            pos_ = (pos_ + run) % size_;
        }
    }
    uint8_t byte() {
        uint8_t b;
        fill(&b, 1);
        return b;
    }
    size_t position() const { return pos_; }
    void seek(size_t pos) { pos_ = size_ ? pos % size_ : 0; }

private:
    const uint8_t* data_;
    size_t size_;
    size_t pos_ = 0;
};

void storeFloat(uint8_t* p, float f) { std::memcpy(p, &f, 4); }
void storeU64(uint8_t* p, uint64_t v) { std::memcpy(p, &v, 8); }
uint64_t loadU64(const uint8_t* p) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    return v;
}

// Small finite floats at every 4-byte position.
void niceFloats(Region& r, fz::Rng& rng) {
    for (size_t i = 0; i + 4 <= r.size; i += 4) storeFloat(r.data + i, rng.uniform(-4.0f, 4.0f));
}

// One geometry and the memory it points to (not movable: pNext points inside).
struct Geometry {
    VkAccelerationStructureGeometryKHR geometry{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
    VkAccelerationStructureGeometrySpheresDataNV spheres{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
    VkAccelerationStructureGeometryLinearSweptSpheresDataNV lss{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV};
    VkAccelerationStructureGeometryMotionTrianglesDataNV motionTriangles{
        VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV};
    VkAccelerationStructureBuildRangeInfoKHR range{};
    uint32_t maxCount = 0;
    std::deque<Region> regions;  // the inputs (a deque: references stay valid as regions are added)
    Region& region(size_t n) {
        regions.emplace_back(n);
        return regions.back();
    }
    Geometry() = default;
    Geometry(const Geometry&) = delete;
};

// What an instance reference in fuzzed data becomes (values below 16 are tokens). `nice` picks a real bottom level
// (in a motion build the motion-triangle one too).
uint64_t instanceReference(Device& d, uint64_t v, bool nice, const Region& pool, bool motion = false) {
    if (nice) v = motion ? (v % 5 == 4 ? 11 : 1 + v % 5) : 1 + v % 4;
    switch (v) {
        case 0: return 0;
        case 1: return uint64_t(d.blasTriangles.handle);
        case 2: return uint64_t(d.blasAabbs.handle);
        case 3: return uint64_t(d.blasSpheres.handle);
        case 4: return uint64_t(d.blasLss.handle);
        case 5: return uint64_t(d.tlas.handle);
        case 6: return uint64_t(d.unbuilt.handle);
        case 7: return d.deadHandle;
        case 8: return uint64_t(fz::plainDevice().blasTriangles.handle);
        case 9: return d.address(d.blasTriangles);
        case 10: return reinterpret_cast<uint64_t>(pool.data);  // harness memory that is no structure
        case 11: return uint64_t(d.blasMotion.handle);
        case 12: return uint64_t(d.tlasMotion.handle);
        default: return v;
    }
}

// ---- [NV-motion] motion instances ---------------------------------------------------------------------------------
// The structure a motion instance's type names (VkAccelerationStructureInstanceKHR, ...MatrixMotionInstanceNV,
// ...SRTMotionInstanceNV): its size, the number of transform floats at its start, and the offset of its
// customIndex|mask word (then sbtOffset|flags, then the reference). An invalid type reads nothing (validation reports
// it first); the harness gives it the largest size.
struct MotionMember {
    uint32_t size, floats, words;
};
MotionMember motionMember(uint32_t type) {
    switch (type) {
        case 0: return {64, 12, 48};
        case 1: return {112, 24, 96};
        default: return {144, 32, 128};
    }
}

// Fills the member structure of a motion instance of `type` (<= 2): nice transforms and mask when `nice`, one
// non-finite transform float when `nonFinite`, the reference a token (instanceReference).
void finishMotionInstance(Device& d, uint32_t type, uint8_t* body, bool nice, bool nonFinite, const Region& pool,
                          fz::Rng& rng) {
    const MotionMember m = motionMember(type);
    if (nice) {
        float f[32] = {};
        if (type == 0 || type == 1) {
            for (int t = 0; t < int(type) + 1; ++t) {
                float* x = f + 12 * t;
                for (int i = 0; i < 12; ++i) x[i] = (i % 5 == 0) ? rng.uniform(0.5f, 2.0f) : rng.uniform(-0.3f, 0.3f);
                x[3] = rng.uniform(-8, 8), x[7] = rng.uniform(-8, 8), x[11] = rng.uniform(-8, 8);
            }
        } else {  // VkSRTDataNV: sx a b pvx sy c pvy sz pvz qx qy qz qw tx ty tz, at time 0 and 1
            for (int t = 0; t < 2; ++t) {
                float* x = f + 16 * t;
                x[0] = rng.uniform(0.5f, 2.0f), x[4] = rng.uniform(0.5f, 2.0f), x[7] = rng.uniform(0.5f, 2.0f);
                x[1] = rng.uniform(-0.3f, 0.3f), x[2] = rng.uniform(-0.3f, 0.3f), x[5] = rng.uniform(-0.3f, 0.3f);
                x[3] = rng.uniform(-1, 1), x[6] = rng.uniform(-1, 1), x[8] = rng.uniform(-1, 1);
                const bool zero = rng.next() % 16 == 0;  // a zero quaternion: the identity rotation
                for (int k = 9; k < 13; ++k) x[k] = zero ? 0.0f : rng.uniform(-1, 1);
                x[13] = rng.uniform(-8, 8), x[14] = rng.uniform(-8, 8), x[15] = rng.uniform(-8, 8);
            }
        }
        std::memcpy(body, f, 4 * m.floats);
        body[m.words + 3] = 0xFF;   // mask
        body[m.words + 7] &= 0x0F;  // flags: the four VkGeometryInstanceFlagBitsKHR of the core extension
    }
    if (nonFinite) {
        const float values[3] = {NAN, INFINITY, -INFINITY};
        storeFloat(body + 4 * (rng.next() % m.floats), values[rng.next() % 3]);
    }
    storeU64(body + m.words + 8, instanceReference(d, loadU64(body + m.words + 8), nice, pool, true));
}

// The instances of a motion build: VkAccelerationStructureMotionInstanceNV records at a 160-byte stride, or typed
// pointers (the low 4 bits the type) to structures of the size their type names, each its own allocation.
void makeMotionInstances(Device& d, const GeomSpec& gs, uint32_t count, uint32_t primitiveOffset, Payload& payload,
                         fz::Rng& rng, Geometry& out) {
    const bool nice = gs.fix & fz::kNiceData;
    const bool nonFinite = gs.motion & fz::kMotionNonFinite;
    auto& in = out.geometry.geometry.instances;
    Region& pool = out.region(64);  // harness memory that is no structure (instance reference token 10)
    auto typeOf = [&](uint32_t raw) -> uint32_t {
        if (gs.motion & fz::kMotionOneType) return uint32_t(gs.motion >> 4) % 3;
        return (gs.motion & fz::kMotionRawType) ? raw : raw % 3;
    };
    if (!in.arrayOfPointers) {
        Region& arr = out.region(primitiveOffset + 160ull * count);
        payload.fill(arr.data, arr.size);
        for (uint32_t k = 0; k < count; ++k) {
            uint8_t* rec = arr.data + primitiveOffset + 160ull * k;
            uint32_t raw;
            std::memcpy(&raw, rec, 4);
            const uint32_t type = typeOf(raw);
            std::memcpy(rec, &type, 4);
            if (!(gs.motion & fz::kMotionFlags)) std::memset(rec + 4, 0, 4);
            if (type <= 2) finishMotionInstance(d, type, rec + 8, nice, nonFinite, pool, rng);
        }
        in.data.hostAddress = (gs.fix & fz::kNullData) ? nullptr : arr.data;
    } else {
        Region& ptrs = out.region(primitiveOffset + 8ull * count);
        payload.fill(ptrs.data, primitiveOffset);
        for (uint32_t k = 0; k < count; ++k) {
            const uint32_t type = typeOf(payload.byte()) & 15;
            Region& body = out.region(motionMember(type).size);  // 16-byte aligned: the low 4 bits are free
            payload.fill(body.data, body.size);
            if (type <= 2) finishMotionInstance(d, type, body.data, nice, nonFinite, pool, rng);
            const uintptr_t p = reinterpret_cast<uintptr_t>(body.data) | type;
            std::memcpy(ptrs.data + primitiveOffset + 8ull * k, &p, sizeof p);
        }
        if ((gs.fix & fz::kFlipIndexPointer) && count) {  // a NULL pointer (with type bits)
            const uintptr_t p = payload.byte() & 15;
            std::memcpy(ptrs.data + primitiveOffset + 8ull * (gs.indexSpan % count), &p, sizeof p);
        }
        in.data.hostAddress = (gs.fix & fz::kNullData) ? nullptr : ptrs.data;
    }
}

// Materializes geometry `gs` of type `kind` into `out`: every region sized for what the parameters can reach.
void makeGeometry(Device& d, const GeomSpec& gs, uint32_t kind, uint8_t geometryFlags, bool motionBuild,
                  Payload& payload, Geometry& out) {
    fz::Rng rng(uint64_t(gs.count) * 0x9E37 + gs.stride + (uint64_t(payload.position()) << 20));
    const bool nice = gs.fix & fz::kNiceData;
    const FormatInfo& fmt = kFormats[gs.format % kFormatCount];
    const VkIndexType indexType = kIndexTypes[gs.indexType % 4];
    const bool indexed = indexType != VK_INDEX_TYPE_NONE_KHR;
    const uint32_t isz = indexSize(indexType);
    uint32_t primitiveOffset = gs.primitiveOffset;
    if (gs.fix & fz::kAlign) primitiveOffset &= ~15u;
    const uint32_t firstVertex = gs.firstVertex % 512;
    auto& g = out.geometry;
    g.geometryType = kGeometryTypes[kind];
    g.flags = (geometryFlags & 3) | ((geometryFlags & 4) ? 0x100u : 0u);
    if ((gs.fix & fz::kBadGeometry) && kind != 3 && kind != 4) g.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
    auto& r = out.range;
    r.primitiveOffset = primitiveOffset;

    if (kind == 0) {  // triangles
        const uint32_t count = gs.count % 300;
        const uint64_t stride = (gs.fix & fz::kAutoStride) ? fmt.size : gs.stride;
        auto& t = g.geometry.triangles;
        t.sType = (gs.fix & fz::kBadSType) ? VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR
                                           : VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = fmt.format;
        t.vertexStride = stride;
        t.indexType = indexType;
        uint64_t maxIndex = 0;
        if (indexed) {
            Region& idx = out.region(primitiveOffset + uint64_t(3) * count * isz);
            payload.fill(idx.data, idx.size);
            const uint32_t span = 1 + gs.indexSpan % 256;
            for (uint64_t k = 0; k < 3ull * count; ++k) {
                uint8_t* p = idx.data + primitiveOffset + k * isz;
                uint32_t value;
                if (nice) {
                    value = uint32_t(rng.next() % span);
                    if (isz == 2) {
                        const uint16_t v16 = uint16_t(value);
                        std::memcpy(p, &v16, 2);
                    } else {
                        std::memcpy(p, &value, 4);
                    }
                }
                if (isz == 2) {
                    uint16_t v16;
                    std::memcpy(&v16, p, 2);
                    value = v16;
                } else {
                    std::memcpy(&value, p, 4);
                }
                maxIndex = std::max<uint64_t>(maxIndex, value);
            }
            t.indexData.hostAddress = (gs.fix & fz::kFlipIndexPointer) ? nullptr : idx.data;
        } else if (gs.fix & fz::kFlipIndexPointer) {
            t.indexData.hostAddress = out.region(16).data;
        }
        uint64_t maxVertex = gs.maxVertex % 2048;
        const uint64_t needed = indexed ? firstVertex + maxIndex : firstVertex + (count ? 3ull * count - 1 : 0);
        if ((gs.fix & fz::kAutoMaxVertex) && needed < 4096) maxVertex = needed;  // else validation rejects it
        t.maxVertex = uint32_t(maxVertex);
        Region& v = out.region((indexed ? 0 : primitiveOffset) + stride * maxVertex + fmt.size);
        payload.fill(v.data, v.size);
        if (nice && fmt.float32) niceFloats(v, rng);
        t.vertexData.hostAddress = (gs.fix & fz::kNullData) ? nullptr : v.data;
        if (gs.motion & fz::kMotionTriangles) {
            // [NV-motion] Time-1 vertices: the same format, stride, indexing and size as the time-0 ones.
            Region& v1 = out.region(v.size);
            payload.fill(v1.data, v1.size);
            if (nice && fmt.float32) {
                if (gs.motion & fz::kMotionNearVertices) {
                    std::memcpy(v1.data, v.data, v.size);
                    for (size_t i = 0; i + 4 <= v1.size; i += 4) {
                        float f;
                        std::memcpy(&f, v1.data + i, 4);
                        storeFloat(v1.data + i, f + rng.uniform(-0.5f, 0.5f));
                    }
                } else {
                    niceFloats(v1, rng);
                }
            }
            auto& m = out.motionTriangles;
            if (gs.motion & fz::kMotionBadSType) m.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_MOTION_INFO_NV;
            m.vertexData.hostAddress = (gs.motion & fz::kMotionNullVertices) ? nullptr : v1.data;
            t.pNext = &m;
        }
        if (gs.transform) {
            uint32_t offset = gs.transform - 1u;
            if (gs.fix & fz::kAlign) offset &= ~15u;
            Region& m = out.region(offset + 48);
            payload.fill(m.data, m.size);
            if (nice) {
                for (int i = 0; i < 12; ++i)
                    storeFloat(m.data + offset + 4 * i, (i % 5 == 0) ? rng.uniform(0.5f, 2.0f) : rng.uniform(-1, 1));
            }
            t.transformData.hostAddress = m.data;
            r.transformOffset = offset;
        }
        r.firstVertex = firstVertex;
        r.primitiveCount = count;
    } else if (kind == 1) {  // AABBs
        const uint32_t count = gs.count % 300;
        const uint64_t stride = (gs.fix & fz::kAutoStride) ? 24 : gs.stride;
        auto& a = g.geometry.aabbs;
        a.sType = (gs.fix & fz::kBadSType) ? VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR
                                           : VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        a.stride = stride;
        Region& box = out.region(primitiveOffset + (count ? stride * (count - 1) : 0) + 24);
        payload.fill(box.data, box.size);
        if (nice && (stride >= 24 || stride == 0)) {
            for (uint32_t i = 0; i < count; ++i) {
                float lo[3], hi[3];
                for (int k = 0; k < 3; ++k) {
                    lo[k] = rng.uniform(-4, 4);
                    hi[k] = lo[k] + rng.uniform(0, 1);
                }
                if (rng.next() % 16 == 0) lo[0] = NAN;  // inactive
                uint8_t* p = box.data + primitiveOffset + stride * i;
                for (int k = 0; k < 3; ++k) storeFloat(p + 4 * k, lo[k]), storeFloat(p + 12 + 4 * k, hi[k]);
            }
        }
        a.data.hostAddress = (gs.fix & fz::kNullData) ? nullptr : box.data;
        r.primitiveCount = count;
    } else if (kind == 2) {  // instances
        const uint32_t count = gs.count % 64;
        auto& in = g.geometry.instances;
        in.sType = (gs.fix & fz::kBadSType) ? VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR
                                            : VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
        in.arrayOfPointers = (gs.instances & 1) ? VK_TRUE : VK_FALSE;
        r.primitiveCount = count;
        if (motionBuild) {
            makeMotionInstances(d, gs, count, primitiveOffset, payload, rng, out);
            out.maxCount = count;
            return;
        }
        Region pool(std::max<size_t>(64 * size_t(count), 64));
        payload.fill(pool.data, pool.size);
        for (uint32_t k = 0; k < count; ++k) {
            uint8_t* rec = pool.data + 64 * k;
            if (nice) {
                float m[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
                m[3] = rng.uniform(-8, 8), m[7] = rng.uniform(-8, 8), m[11] = rng.uniform(-8, 8);
                std::memcpy(rec, m, 48);
                rec[51] = 0xFF;  // mask
                rec[55] &= 0x0F;  // flags: the four VkGeometryInstanceFlagBitsKHR of the core extension
            }
            storeU64(rec + 56, instanceReference(d, loadU64(rec + 56), nice, pool));
        }
        if (!in.arrayOfPointers) {
            Region& arr = out.region(primitiveOffset + 64ull * count);
            payload.fill(arr.data, primitiveOffset);
            std::memcpy(arr.data + primitiveOffset, pool.data, 64ull * count);
            in.data.hostAddress = (gs.fix & fz::kNullData) ? nullptr : arr.data;
        } else {
            Region& ptrs = out.region(primitiveOffset + 8ull * count);
            payload.fill(ptrs.data, primitiveOffset);
            for (uint32_t k = 0; k < count; ++k) {
                const uint32_t which = nice ? k : payload.byte() % count;
                const uint8_t* p = pool.data + 64 * which;
                std::memcpy(ptrs.data + primitiveOffset + 8ull * k, &p, sizeof p);
            }
            if ((gs.fix & fz::kFlipIndexPointer) && count) {
                const void* null = nullptr;
                std::memcpy(ptrs.data + primitiveOffset + 8ull * (gs.indexSpan % count), &null, sizeof null);
            }
            in.data.hostAddress = (gs.fix & fz::kNullData) ? nullptr : ptrs.data;
        }
        out.regions.push_back(std::move(pool));
        r.primitiveCount = count;
    } else {  // spheres (3), LSS (4)
        const bool lss = kind == 4;
        const uint32_t count = gs.count % 300;
        const uint64_t stride = (gs.fix & fz::kAutoStride) ? fmt.size : gs.stride;
        const VkFormat radiusFormats[4] = {VK_FORMAT_R32_SFLOAT, VK_FORMAT_R16_SFLOAT, VK_FORMAT_R8_UNORM,
                                           VK_FORMAT_R32_SFLOAT};
        const VkFormat radiusFormat = radiusFormats[gs.radius & 3];
        const uint32_t rsz = radiusFormat == VK_FORMAT_R16_SFLOAT ? 2 : 4;
        const uint64_t radiusStride = (gs.fix & fz::kAutoStride) ? rsz : (gs.radius >> 2);
        const bool successive = lss && (gs.lss & 1);
        const uint32_t reads = !lss ? count : successive ? count : 2 * count;  // index (or vertex) reads
        uint64_t vertices;  // vertex numbers 0 .. vertices - 1 (firstVertex included) can be read
        uint64_t indexStride = 0;
        const uint8_t* indexPointer = nullptr;
        if (indexed) {
            // Index values are kept below `span` (vkas cannot check them: spheres have no maxVertex). Slots never
            // overlap: the stride is a multiple of the index size.
            indexStride = isz * ((gs.fix & fz::kAutoStride) ? 1u : ((gs.lss >> 3) & 3u));
            const uint32_t span = 1 + gs.indexSpan % 256;
            Region& idx = out.region(primitiveOffset + (reads ? indexStride * (reads - 1) : 0) + isz);
            payload.fill(idx.data, idx.size);
            for (uint32_t n = 0; n < reads; ++n) {
                uint8_t* p = idx.data + primitiveOffset + indexStride * n;
                const uint32_t value = nice ? n % span : uint32_t(rng.next() % span);
                if (isz == 2) {
                    const uint16_t v16 = uint16_t(value);
                    std::memcpy(p, &v16, 2);
                } else {
                    std::memcpy(p, &value, 4);
                }
            }
            indexPointer = idx.data;
            vertices = firstVertex + span + (successive ? 1 : 0);
        } else {
            vertices = firstVertex + (successive ? uint64_t(count) + 1 : reads);
        }
        vertices = std::max<uint64_t>(vertices, 1);
        const uint64_t base = indexed ? 0 : primitiveOffset;
        Region& v = out.region(base + stride * (vertices - 1) + fmt.size);
        payload.fill(v.data, v.size);
        if (nice && fmt.float32) niceFloats(v, rng);
        Region& rad = out.region(base + radiusStride * (vertices - 1) + rsz);
        payload.fill(rad.data, rad.size);
        if (nice) {
            for (uint64_t k = 0; k < vertices; ++k) {
                uint8_t* p = rad.data + base + radiusStride * k;
                if (rsz == 4) {
                    storeFloat(p, rng.uniform(0.05f, 0.5f));
                } else {
                    const uint16_t h = uint16_t(0x3000 + rng.next() % 0x800);  // 0.125 .. 0.5
                    std::memcpy(p, &h, 2);
                }
            }
        }
        const void* vertexData = (gs.fix & fz::kNullData) ? nullptr : v.data;
        const void* indexData = indexed ? ((gs.fix & fz::kFlipIndexPointer) ? nullptr : indexPointer)
                                        : ((gs.fix & fz::kFlipIndexPointer) ? v.data : nullptr);
        const VkStructureType bad = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        if (lss) {
            auto& l = out.lss;
            if (gs.fix & fz::kBadSType) l.sType = bad;
            l.vertexFormat = fmt.format;
            l.vertexData.hostAddress = vertexData;
            l.vertexStride = stride;
            l.radiusFormat = radiusFormat;
            l.radiusData.hostAddress = rad.data;
            l.radiusStride = radiusStride;
            l.indexType = indexType;
            l.indexData.hostAddress = indexData;
            l.indexStride = indexStride;
            l.indexingMode = (gs.lss & 4) ? VkRayTracingLssIndexingModeNV(7)
                             : successive ? VK_RAY_TRACING_LSS_INDEXING_MODE_SUCCESSIVE_NV
                                          : VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV;
            l.endCapsMode = (gs.lss & 4) ? VkRayTracingLssPrimitiveEndCapsModeNV(7)
                            : (gs.lss & 2) ? VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_CHAINED_NV
                                           : VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV;
            if (!(gs.fix & fz::kBadGeometry)) g.pNext = &l;
        } else {
            auto& s = out.spheres;
            if (gs.fix & fz::kBadSType) s.sType = bad;
            s.vertexFormat = fmt.format;
            s.vertexData.hostAddress = vertexData;
            s.vertexStride = stride;
            s.radiusFormat = radiusFormat;
            s.radiusData.hostAddress = rad.data;
            s.radiusStride = radiusStride;
            s.indexType = indexType;
            s.indexData.hostAddress = indexData;
            s.indexStride = indexStride;
            if (!(gs.fix & fz::kBadGeometry)) g.pNext = &s;
        }
        r.firstVertex = firstVertex;
        r.primitiveCount = count;
    }
    out.maxCount = r.primitiveCount;
}

// A set of geometries of one info.
struct GeometrySet {
    std::unique_ptr<Geometry[]> g{new Geometry[3]};
    uint32_t count = 0;
    VkAccelerationStructureGeometryKHR plain[3];
    const VkAccelerationStructureGeometryKHR* pointers[3];
    VkAccelerationStructureBuildRangeInfoKHR ranges[3];
    uint32_t maxCounts[3];
    uint32_t actualCounts[3];
};

void makeSet(Device& d, const BuildSpec& spec, uint32_t kind, uint32_t geometryCount, bool maxDelta, Payload& payload,
             GeometrySet& set) {
    set.count = geometryCount;
    for (uint32_t i = 0; i < geometryCount; ++i) {
        const uint32_t k = (i == 1 && (spec.geometryCount & 0x40)) ? (kind + 1) % 5 : kind;
        makeGeometry(d, spec.g[i], k, spec.g[i].flags, spec.motion & 1, payload, set.g[i]);
        set.plain[i] = set.g[i].geometry;  // pNext still points into set.g[i], which never moves
        set.pointers[i] = &set.g[i].geometry;
        set.ranges[i] = set.g[i].range;
        set.actualCounts[i] = set.ranges[i].primitiveCount;
        const int64_t m = int64_t(set.ranges[i].primitiveCount) + (maxDelta ? spec.g[i].maxCountDelta : 0);
        set.maxCounts[i] = uint32_t(std::max<int64_t>(m, 0));
    }
}

VkBuildAccelerationStructureFlagsKHR buildFlags(uint8_t bits) {
    VkBuildAccelerationStructureFlagsKHR f = bits & 0x1F;
    if (bits & 0x20) f |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_DATA_ACCESS_KHR;
    if (bits & 0x40) f |= 0x40000000u;
    return f;
}

// Memory whose bytes a failed call must not change.
struct Watched {
    const uint8_t* data;
    size_t size;
    std::vector<uint8_t> before;
    const char* what;
};
void watch(std::vector<Watched>& w, const uint8_t* data, size_t size, const char* what) {
    w.push_back({data, size, std::vector<uint8_t>(data, data + size), what});
}
bool unchanged(const Watched& w) { return w.size == 0 || std::memcmp(w.data, w.before.data(), w.size) == 0; }

VkResult submit(Device& d, bool deferred, uint32_t infoCount, const VkAccelerationStructureBuildGeometryInfoKHR* infos,
                const VkAccelerationStructureBuildRangeInfoKHR* const* ranges, uint64_t& reported) {
    const uint64_t before = d.messages();
    if (!deferred) {
        VkResult r = d.vkBuildAccelerationStructuresKHR(d.device, VK_NULL_HANDLE, infoCount, infos, ranges);
        reported = d.messages() - before;
        return r;
    }
    VkDeferredOperationKHR op;
    FZ_CHECK(d.vkCreateDeferredOperationKHR(d.device, nullptr, &op) == VK_SUCCESS, "vkCreateDeferredOperationKHR");
    VkResult r = d.vkBuildAccelerationStructuresKHR(d.device, op, infoCount, infos, ranges);
    reported = d.messages() - before;
    if (r == VK_OPERATION_DEFERRED_KHR) {
        FZ_CHECK(reported == 0, "deferred after %llu validation message(s)", (unsigned long long)reported);
        VkResult j;
        int rounds = 0;
        while ((j = d.vkDeferredOperationJoinKHR(d.device, op)) == VK_THREAD_IDLE_KHR)
            FZ_CHECK(++rounds < 1000000, "a deferred build never completes");
        FZ_CHECK(j == VK_SUCCESS || j == VK_THREAD_DONE_KHR, "vkDeferredOperationJoinKHR returned %d", int(j));
        r = d.vkGetDeferredOperationResultKHR(d.device, op);
    }
    d.vkDestroyDeferredOperationKHR(d.device, op, nullptr);
    return r;
}

// After a successful build: serialization accepts what the builder wrote and loads it back identically; rays.
void exercise(Device& d, Structure& s, VkAccelerationStructureTypeKHR type, const uint8_t* seed, size_t seedSize) {
    const VkDeviceSize used = d.usedSize(s);
    FZ_CHECK(used >= 256 && used <= s.size, "usedSize %llu of a structure of %llu bytes", (unsigned long long)used,
             (unsigned long long)s.size);
    VkDeviceSize size = 0;
    FZ_CHECK(d.vkWriteAccelerationStructuresPropertiesKHR(d.device, 1, &s.handle,
                                                          VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                                          sizeof size, &size, sizeof size) == VK_SUCCESS,
             "SERIALIZATION_SIZE query");
    Region blob(size, 0xAA);
    VkCopyAccelerationStructureToMemoryInfoKHR sc{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    sc.src = s.handle;
    sc.dst.hostAddress = blob.data;
    sc.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    FZ_CHECK(d.vkCopyAccelerationStructureToMemoryKHR(d.device, VK_NULL_HANDLE, &sc) == VK_SUCCESS, "serialize");
    Structure copy = d.createStructure(type, (used + 255) / 256 * 256);
    VkCopyMemoryToAccelerationStructureInfoKHR dc{VK_STRUCTURE_TYPE_COPY_MEMORY_TO_ACCELERATION_STRUCTURE_INFO_KHR};
    dc.src.hostAddress = blob.data;
    dc.dst = copy.handle;
    dc.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_DESERIALIZE_KHR;
    const uint64_t before = d.messages();
    const VkResult r = d.vkCopyMemoryToAccelerationStructureKHR(d.device, VK_NULL_HANDLE, &dc);
    FZ_CHECK(r == VK_SUCCESS && d.messages() == before, "vkas rejects (%d) the serialized form of a structure it built",
             int(r));
    FZ_CHECK(std::memcmp(copy.block(), s.block(), used) == 0, "serialize + load changed the structure");
    d.destroyStructure(copy);

    float bounds[6];
    std::memcpy(bounds, s.block() + 32, sizeof bounds);
    if (type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR) {
        fz::traceProbe(d, s.handle, bounds, seed, seedSize);
    } else {
        // A bottom level built with motion goes into a motion top level (an instance type the seed chooses); others
        // now and then too.
        const uint8_t pick = seedSize > 1 ? seed[1] : 0;
        const int motionType = (fz::builtWithMotion(s.block()) || (pick & 4)) ? int(pick % 3) : -1;
        Structure top = d.buildSingleInstanceTlas(s, seedSize ? seed[0] : 0, motionType);
        fz::traceProbe(d, top.handle, bounds, seed, seedSize);
        d.destroyStructure(top);
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > (1u << 16)) return 0;
    BuildSpec spec{};
    std::memcpy(&spec, data, std::min(size, sizeof spec));
    const uint8_t* payloadData = size > sizeof spec ? data + sizeof spec : nullptr;
    const size_t payloadSize = size > sizeof spec ? size - sizeof spec : 0;
    Payload payload(payloadData, payloadSize);
    Device& d = fz::validatingDevice();

    const uint32_t kind = spec.kind % 5;
    const bool top = kind == 2;
    const uint32_t geometryCount = top ? ((spec.geometryCount & 0x80) ? spec.geometryCount % 4 : 1) : spec.geometryCount % 4;
    const bool update = spec.mode & 1, inPlace = update && (spec.mode & 2), deferred = spec.mode & 4;
    const bool usePointers = spec.mode & 8, twoInfos = !update && (spec.mode & 16);
    VkAccelerationStructureTypeKHR type = top ? VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR
                                              : VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    const VkAccelerationStructureTypeKHR otherType = top ? VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR
                                                         : VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    const bool motion = spec.motion & 1;
    const VkBuildAccelerationStructureFlagsKHR flags =
        buildFlags(spec.buildFlags) | (motion ? VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV : 0);
    const VkDeviceSize asOffset = (spec.asOffset & 1) ? 256 : 0;
    // [NV-motion] The structures of a motion build are created with CREATE_MOTION (the destination, with bit 1, the
    // other way); a top level's VkAccelerationStructureMotionInfoNV::maxInstances is a hint (bit 2: 0).
    const VkAccelerationStructureCreateFlagsKHR srcCreate = motion ? VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV : 0;
    const VkAccelerationStructureCreateFlagsKHR dstCreate =
        (spec.motion & 2) ? (srcCreate ^ VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV) : srcCreate;
    const uint32_t maxInstances = (spec.motion & 4) ? 0 : 64;

    GeometrySet set;
    makeSet(d, spec, kind, geometryCount, (spec.dstSize & 3) == 3, payload, set);

    VkAccelerationStructureBuildGeometryInfoKHR info{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR};
    info.type = (spec.mode & 64) ? VK_ACCELERATION_STRUCTURE_TYPE_GENERIC_KHR : type;
    info.flags = flags;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = geometryCount;
    if (usePointers) info.ppGeometries = set.pointers;
    else info.pGeometries = set.plain;
    if (spec.misc & 4) info.pGeometries = set.plain, info.ppGeometries = set.pointers;
    if (spec.misc & 8) info.pGeometries = nullptr, info.ppGeometries = nullptr;
    if (spec.misc & 1) info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;

    // Sizes: the query the application makes (its counts), and the scratch the actual counts need.
    VkAccelerationStructureBuildSizesInfoKHR sizes{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    sizes.accelerationStructureSize = sizes.buildScratchSize = sizes.updateScratchSize = 0xDEADull;
    uint64_t before = d.messages();
    d.vkGetAccelerationStructureBuildSizesKHR(d.device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                              set.maxCounts, &sizes);
    const bool sizesReported = d.messages() != before;
    if (sizesReported) {
        FZ_CHECK(sizes.accelerationStructureSize == 0xDEAD && sizes.buildScratchSize == 0xDEAD,
                 "vkGetAccelerationStructureBuildSizesKHR wrote its result after reporting");
        sizes.accelerationStructureSize = 4096;
    }
    VkAccelerationStructureBuildSizesInfoKHR actual{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR};
    before = d.messages();
    d.vkGetAccelerationStructureBuildSizesKHR(d.device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &info,
                                              set.actualCounts, &actual);
    if (d.messages() != before) {
        uint64_t n = 0;
        for (uint32_t i = 0; i < geometryCount; ++i) n += set.actualCounts[i];
        actual.buildScratchSize = n ? 64 + n * (32 + 256) : 0;  // more than any record size needs
    }
    const uint32_t scratchOffset = spec.scratch >> 2;
    const VkDeviceSize scratchSize = update ? std::max<VkDeviceSize>(actual.updateScratchSize, 1) : actual.buildScratchSize;
    VkDeviceSize dstSize = sizes.accelerationStructureSize;
    if ((spec.dstSize & 3) == 1) dstSize += 256;
    if ((spec.dstSize & 3) == 2) dstSize -= std::min<VkDeviceSize>(dstSize, (spec.dstSize >> 2) + 1);
    dstSize = std::clamp<VkDeviceSize>(dstSize, 1, 64u << 20);

    // The source of an update: a build of the same inputs with ALLOW_UPDATE (which validation may refuse).
    Structure src;
    if (update) {
        src = d.createStructure(type, std::max<VkDeviceSize>(sizes.accelerationStructureSize, 256), asOffset, 0,
                                srcCreate, maxInstances);
        VkAccelerationStructureBuildGeometryInfoKHR pre = info;
        pre.flags |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
        pre.dstAccelerationStructure = src.handle;
        Region preScratch(std::max<VkDeviceSize>(actual.buildScratchSize, 1));
        pre.scratchData.hostAddress = preScratch.data;
        const VkAccelerationStructureBuildRangeInfoKHR* preRanges[1] = {set.ranges};
        uint64_t preReported = 0;
        const VkResult pr = submit(d, false, 1, &pre, preRanges, preReported);
        FZ_CHECK((pr == VK_SUCCESS) == (preReported == 0), "update source build: result %d with %llu message(s)",
                 int(pr), (unsigned long long)preReported);
    }
    // The update's inputs: the build's, changed as spec.update says.
    GeometrySet changed;
    const GeometrySet* inputs = &set;
    if (update && spec.update) {
        BuildSpec u = spec;
        for (uint32_t i = 0; i < 3; ++i) {
            GeomSpec& g = u.g[i];
            if (spec.update & 1) g.count = uint16_t(g.count % 300 + 1);
            if (spec.update & 8) g.maxVertex = uint16_t(g.maxVertex + 1), g.fix &= uint8_t(~fz::kAutoMaxVertex);
            if (spec.update & 16) g.format = uint8_t(g.format + 1);
            if (spec.update & 32) g.transform = g.transform ? 0 : 1;
            if (spec.update & 64) g.flags ^= 1;
            if (spec.update & 128) g.indexType = uint8_t(g.indexType + 1);
        }
        if (!(spec.update & 2)) payload.seek(0);  // same data
        makeSet(d, u, kind, geometryCount, false, payload, changed);
        inputs = &changed;
    }

    // Destination(s) and scratch.
    const bool wrongType = spec.mode & 32;
    const uint32_t infoCount = (spec.misc & 16) ? 0 : twoInfos ? 2 : 1;
    Structure dst[2];
    Region scratch[2];
    Region garbage(64, 0x41);  // harness memory that is no structure
    VkAccelerationStructureBuildGeometryInfoKHR infos[2];
    const VkAccelerationStructureBuildRangeInfoKHR* rangePointers[2];
    std::vector<Watched> watched;
    for (uint32_t i = 0; i < std::max(infoCount, 1u); ++i) {
        const bool overlap = spec.scratch & 2;
        if (inPlace) {
            dst[i] = src;
        } else {
            dst[i] = d.createStructure(wrongType ? otherType : type, dstSize, asOffset,
                                       overlap ? asOffset + scratchOffset + scratchSize : 0, dstCreate, maxInstances);
        }
        infos[i] = info;
        infos[i].flags = flags;
        if (update) {  // the source was built with ALLOW_UPDATE; the update's flags must be the same
            infos[i].flags |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
            if (spec.update & 4) infos[i].flags ^= VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
        }
        if (update) {
            infos[i].mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_UPDATE_KHR;
            infos[i].srcAccelerationStructure = (spec.misc & 32) ? VkAccelerationStructureKHR(d.deadHandle) : src.handle;
        }
        if (spec.mode & 128) infos[i].mode = VkBuildAccelerationStructureModeKHR(2);
        // The update's inputs in whichever of the two arrays the build info names (misc bit 8: neither, which the
        // size query above reported: the build must report it too, so no array may be put back here).
        if (infos[i].pGeometries) infos[i].pGeometries = inputs->plain;
        if (infos[i].ppGeometries) infos[i].ppGeometries = inputs->pointers;
        infos[i].dstAccelerationStructure = dst[i].handle;
        if (spec.misc & 64) infos[i].dstAccelerationStructure = reinterpret_cast<VkAccelerationStructureKHR>(garbage.data);
        if (overlap) {
            infos[i].scratchData.hostAddress = dst[i].block() + scratchOffset;
        } else {
            scratch[i] = Region(scratchOffset + scratchSize, 0xAA);
            infos[i].scratchData.hostAddress = (spec.scratch & 1) ? nullptr : scratch[i].data + scratchOffset;
            watch(watched, scratch[i].data, scratch[i].size, "scratch");
        }
        rangePointers[i] = (spec.misc & 2) ? nullptr : inputs->ranges;
        watch(watched, dst[i].buffer.data, dst[i].buffer.size, "destination buffer");
    }
    if (update && !inPlace) watch(watched, src.buffer.data, src.buffer.size, "update source buffer");
    const size_t firstInput = watched.size();
    for (const GeometrySet* s : {&set, &changed})
        for (uint32_t i = 0; i < s->count; ++i)
            for (const Region& r : s->g[i].regions) watch(watched, r.data, r.size, "build input");

    uint64_t reported = 0;
    const VkResult r = submit(d, deferred, infoCount, infos, rangePointers, reported);
    if (std::getenv("VKAS_FUZZ_VERBOSE"))
        std::fprintf(stderr, "vkas fuzz: the build returned %d after %llu validation message(s)%s\n", int(r),
                     (unsigned long long)reported, motion ? " (a motion build)" : "");
    for (size_t i = firstInput; i < watched.size(); ++i)
        FZ_CHECK(unchanged(watched[i]), "the build wrote into its %s", watched[i].what);
    if (reported != 0) {
        FZ_CHECK(r == VK_ERROR_VALIDATION_FAILED_EXT, "result %d after %llu validation message(s)", int(r),
                 (unsigned long long)reported);
        for (size_t i = 0; i < firstInput; ++i)
            FZ_CHECK(unchanged(watched[i]), "a build that failed validation changed its %s", watched[i].what);
    } else {
        FZ_CHECK(r == VK_SUCCESS, "result %d for a build validation accepted", int(r));
        FZ_CHECK(!sizesReported, "the size query reported what the build accepted");
        const size_t seedOff = std::min<size_t>(payloadSize, 0);
        for (uint32_t i = 0; i < infoCount; ++i) {
            uint64_t headerUsed;  // the header's usedSize (docs/FORMAT.md): the bytes the build wrote
            std::memcpy(&headerUsed, dst[i].block() + 16, 8);
            FZ_CHECK(headerUsed <= dst[i].size, "the build wrote %llu bytes into a structure of %llu (size query: %llu)",
                     (unsigned long long)headerUsed, (unsigned long long)dst[i].size,
                     (unsigned long long)sizes.accelerationStructureSize);
            const VkDeviceSize used = d.usedSize(dst[i]);
            // Nothing of the buffer outside [offset, offset + usedSize) was written (scratch inside it aside).
            if (!inPlace && !(spec.scratch & 2)) {
                const Buffer& b = dst[i].buffer;
                for (size_t k = 0; k < b.size; ++k)
                    if (k < dst[i].offset || k >= dst[i].offset + used)
                        FZ_CHECK(b.data[k] == 0xAA, "the build wrote byte %zu of its buffer, outside the %llu used bytes at offset %llu",
                                 k, (unsigned long long)used, (unsigned long long)dst[i].offset);
            }
            uint32_t builtType;  // the header's type (docs/FORMAT.md): 0 top level
            std::memcpy(&builtType, dst[i].block() + 8, 4);
            const VkAccelerationStructureTypeKHR loaded = builtType == 0 ? VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR
                                                                         : VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
            exercise(d, dst[i], loaded, payloadData + seedOff, std::min<size_t>(payloadSize, 128));
        }
    }
    for (uint32_t i = 0; i < std::max(infoCount, 1u); ++i)
        if (!inPlace) d.destroyStructure(dst[i]);
    if (update) d.destroyStructure(src);
    return 0;
}
