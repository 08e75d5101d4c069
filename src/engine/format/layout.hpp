// The in-memory format of a vkas acceleration structure (docs/FORMAT.md describes it byte by byte).
//
// A structure is one contiguous block at the start of [offset, offset + size) of its buffer:
//   Header | GeometryDesc[geometryCount] | Node[nodeCount] | triangle leaves, AabbRecord[] or InstanceRecord[]
// Every offset inside is relative to the start of the block, so a byte copy of the first usedSize bytes is a
// valid clone. Nodes are 8 wide with their child boxes stored as structure-of-arrays for SIMD box tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace vkas::format {

constexpr uint32_t kMagic = 0x5341'4B56u;  // "VKAS" read as little-endian bytes
// Format 2 stores the triangles of a (non-motion) bottom level as structure-of-arrays leaves (TriangleLeaf below);
// format 1 stored 48-byte TriangleRecords. Blocks of format 1 still load: format/convert.hpp rewrites them.
constexpr uint32_t kVersion = 2;
constexpr uint32_t kFormat1 = 1;
constexpr uint32_t kNodeWidth = 8;
constexpr uint32_t kMaxPrimitivesPerLeaf = 4;  // triangles or AABBs
constexpr uint32_t kMaxInstancesPerLeaf = 1;
// Binary split depth after which the builder stops using the SAH and halves ranges instead. It bounds the tree
// depth, which bounds the traversal stack a ray query carries (see trace/traversal_steps.hpp, kStackCapacity).
constexpr uint32_t kSahDepthLimit = 32;
constexpr uint32_t kMaxTreeDepth = kSahDepthLimit + 32;

enum class StructureType : uint32_t { TopLevel = 0, BottomLevel = 1 };  // VkAccelerationStructureTypeKHR values

// A child reference. 0 is an empty slot. Bits 62-63 give the kind.
//   internal: kind 1, bits 0-31 node index
//   leaf:     kind 2, bits 0-39 first record index, bits 40-47 record count (1-255)
using ChildRef = uint64_t;
constexpr ChildRef kEmptyRef = 0;
constexpr uint64_t kKindShift = 62;
constexpr uint64_t kKindInternal = 1;
constexpr uint64_t kKindLeaf = 2;

constexpr ChildRef makeInternalRef(uint32_t nodeIndex) { return (kKindInternal << kKindShift) | nodeIndex; }
constexpr ChildRef makeLeafRef(uint64_t first, uint32_t count) {
    return (kKindLeaf << kKindShift) | (uint64_t(count) << 40) | (first & 0xFF'FFFF'FFFFull);
}
constexpr bool isInternal(ChildRef r) { return (r >> kKindShift) == kKindInternal; }
constexpr bool isLeaf(ChildRef r) { return (r >> kKindShift) == kKindLeaf; }
constexpr uint32_t nodeIndex(ChildRef r) { return uint32_t(r); }
constexpr uint64_t leafFirst(ChildRef r) { return r & 0xFF'FFFF'FFFFull; }
constexpr uint32_t leafCount(ChildRef r) { return uint32_t((r >> 40) & 0xFF); }

struct Header {
    uint32_t magic;
    uint32_t version;
    uint32_t type;        // StructureType
    uint32_t buildFlags;  // VkBuildAccelerationStructureFlagsKHR of the last build
    uint64_t usedSize;    // bytes from the start of the block that the structure occupies
    ChildRef root;
    float bounds[6];  // lower xyz, upper xyz of everything in the tree (+inf/-inf when empty)
    uint32_t geometryCount;
    uint32_t primitiveCount;  // primitives (or instances) given to the build, inactive ones included
    uint32_t recordCount;     // records stored in the tree
    uint32_t nodeCount;
    uint64_t geometryOffset;
    uint64_t nodeOffset;
    uint64_t recordOffset;
    // VkGeometryTypeKHR of the records: TRIANGLES (0), AABBS (1), INSTANCES (2), SPHERES_NV (1000429004) or
    // LINEAR_SWEPT_SPHERES_NV (1000429005). A bottom-level structure holds
    // one geometry type only (VUID 03792), so traversal branches on it once per instance, not per record.
    uint32_t primitiveType;
    uint32_t reserved0;
    // [EXT-OMM] The opacity micromaps of a bottom level of triangles (format/opacity_section.hpp): where their section
    // starts and the bytes the build reserved for it (an update that changes micromaps rewrites it in place), or 0 and
    // 0 when no geometry has one. Blocks written before micromaps have zeros here.
    uint64_t opacityOffset;
    uint64_t opacityReserved;
    // PREFER_FAST_TRACE with spatial splits (format/fragment_section.hpp): the fragment section after the triangle
    // array, the region of every record that stands for part of a split triangle, or 0 and 0 when no triangle was
    // split. Blocks written before spatial splits have zeros here.
    uint64_t fragmentOffset;
    uint32_t fragmentCount;
    uint32_t reserved1;
    uint8_t reserved[256 - 136];
};
static_assert(sizeof(Header) == 256);

// Per-geometry facts of the last build: flags for traversal, the rest for update validation.
struct GeometryDesc {
    uint32_t geometryType;  // VkGeometryTypeKHR
    uint32_t flags;         // VkGeometryFlagsKHR
    uint32_t primitiveCount;
    uint32_t vertexFormat;  // triangles: VkFormat
    uint32_t indexType;     // triangles: VkIndexType
    uint32_t maxVertex;
    uint32_t hasTransform;
    // Indexed triangles of an ALLOW_UPDATE build: a hash of the index values the build read (refit.hpp,
    // referencedIndexHash), so an update can check VUID 03768 without a copy of the indices. Otherwise 0.
    uint32_t indexHash;
};
static_assert(sizeof(GeometryDesc) == 32);

struct alignas(64) Node {
    float lowerX[kNodeWidth], upperX[kNodeWidth];
    float lowerY[kNodeWidth], upperY[kNodeWidth];
    float lowerZ[kNodeWidth], upperZ[kNodeWidth];
    ChildRef child[kNodeWidth];
};
static_assert(sizeof(Node) == 256);

// A node's slots are written through these, the one place that says what a slot holds (issue 37): a used slot its
// child's box and reference; an empty slot the box +inf / -inf, which no ray enters (trace/node_intersector_sse.hpp: tNear
// is never finite), and kEmptyRef, which a traversal pops as neither node nor leaf (check.cpp refuses one with
// payload bits).
inline void setSlotBox(Node& n, uint32_t i, const float lower[3], const float upper[3]) {
    n.lowerX[i] = lower[0], n.lowerY[i] = lower[1], n.lowerZ[i] = lower[2];
    n.upperX[i] = upper[0], n.upperY[i] = upper[1], n.upperZ[i] = upper[2];
}
inline void setSlot(Node& n, uint32_t i, const float lower[3], const float upper[3], ChildRef ref) {
    setSlotBox(n, i, lower, upper);
    n.child[i] = ref;
}
inline void setEmptySlot(Node& n, uint32_t i) {
    constexpr float kLower[3] = {__builtin_inff(), __builtin_inff(), __builtin_inff()};
    constexpr float kUpper[3] = {-__builtin_inff(), -__builtin_inff(), -__builtin_inff()};
    setSlot(n, i, kLower, kUpper, kEmptyRef);
}

// Triangle record flags.
constexpr uint32_t kTriangleOpaque = 0x1;      // the geometry's OPAQUE flag
constexpr uint32_t kTriangleDegenerate = 0x2;  // kept for updates, never hit
constexpr uint32_t kTriangleNoDuplicateAnyHit = 0x4;
// [EXT-OMM] The geometry has an opacity micromap: the section at Header::opacityOffset decides the triangle's opacity.
constexpr uint32_t kTriangleMicromap = 0x10;
// A fragment of a triangle that a spatial split cut into several records (format/fragment_section.hpp): it reports a
// hit only inside its region, so every point of the triangle is reported by exactly one of its records.
constexpr uint32_t kTriangleFragment = 0x20;
// AABB record flags: the same bits as for triangles.
constexpr uint32_t kAabbOpaque = kTriangleOpaque;
constexpr uint32_t kAabbNoDuplicateAnyHit = kTriangleNoDuplicateAnyHit;

// One triangle as the build gathers it (and as format 1 stored it): the build's temporary record, the base of a
// motion triangle record, and what a triangle leaf is written from.
struct TriangleRecord {
    float v[3][3];  // object-space positions after the geometry transform, application vertex order
    uint32_t geometryIndex;
    uint32_t primitiveIndex;
    uint32_t flags;
};
static_assert(sizeof(TriangleRecord) == 48);

// Format 2: the triangles of a non-motion bottom level. A leaf of n triangles that starts at triangle number `first`
// (its reference's leafFirst) occupies 44 * n bytes at recordOffset + 44 * first, as structure-of-arrays:
//   f32 v0x[n], v0y[n], v0z[n], v1x[n], v1y[n], v1z[n], v2x[n], v2y[n], v2z[n]   (row r = 3 * vertex + axis)
//   u32 primitiveIndex[n]
//   u32 geometryAndFlags[n]: bits 0-23 geometryIndex, bits 24-31 the record flags (kTriangle*)
// so a 4-lane test loads each row with one unaligned load (lanes past n are masked off). The last row of a leaf of
// one triangle reads 4 bytes past the leaf: the triangle array ends with kTriangleTailBytes zero bytes.
constexpr uint64_t kTriangleBytes = 44;
constexpr uint64_t kTriangleTailBytes = 4;
constexpr uint32_t kTriangleRows = 9;
constexpr uint32_t kGeometryIndexBits = 24;
constexpr uint32_t kGeometryIndexMask = (1u << kGeometryIndexBits) - 1;
constexpr uint32_t packGeometryAndFlags(uint32_t geometryIndex, uint32_t flags) {
    return (geometryIndex & kGeometryIndexMask) | (flags << kGeometryIndexBits);
}

// A view of one triangle leaf: where its rows and per-lane words are (the bytes may be unaligned for floats only to
// 4 bytes, which every access here allows).
template <class Byte>
struct TriangleLeafView {
    Byte* base;  // recordOffset + kTriangleBytes * first
    uint32_t n;
    auto* row(uint32_t r) const { return reinterpret_cast<std::conditional_t<std::is_const_v<Byte>, const float, float>*>(base) + r * n; }
    auto* primitiveIndex() const { return reinterpret_cast<std::conditional_t<std::is_const_v<Byte>, const uint32_t, uint32_t>*>(base) + kTriangleRows * n; }
    auto* geometryAndFlags() const { return primitiveIndex() + n; }
    uint32_t geometryIndex(uint32_t lane) const { return geometryAndFlags()[lane] & kGeometryIndexMask; }
    uint32_t flags(uint32_t lane) const { return geometryAndFlags()[lane] >> kGeometryIndexBits; }
    void positions(uint32_t lane, float v[3][3]) const {
        // Row r + 1 lies n floats past row r: one pointer stepped by the leaf size (a hit's positions are read for
        // every committed hit; nine products of row and leaf size cost more than the loads).
        const auto* p = row(0) + lane;
        const size_t stride = n;
        v[0][0] = p[0], v[0][1] = p[stride], v[0][2] = p[2 * stride];
        p += 3 * stride;
        v[1][0] = p[0], v[1][1] = p[stride], v[1][2] = p[2 * stride];
        p += 3 * stride;
        v[2][0] = p[0], v[2][1] = p[stride], v[2][2] = p[2 * stride];
    }
    // Writers (mutable leaves): a lane's positions, or the whole lane from a gathered (or format-1) record.
    void setPositions(uint32_t lane, const float (*v)[3]) const {
        for (uint32_t k = 0; k < 3; ++k)
            for (uint32_t a = 0; a < 3; ++a) row(3 * k + a)[lane] = v[k][a];
    }
    void setLane(uint32_t lane, const TriangleRecord& t) const {
        setPositions(lane, t.v);
        primitiveIndex()[lane] = t.primitiveIndex;
        geometryAndFlags()[lane] = packGeometryAndFlags(t.geometryIndex, t.flags);
    }
};
using ConstTriangleLeaf = TriangleLeafView<const std::byte>;
using MutableTriangleLeaf = TriangleLeafView<std::byte>;
inline ConstTriangleLeaf triangleLeaf(const std::byte* records, uint64_t first, uint32_t n) {
    return {records + kTriangleBytes * first, n};
}
inline MutableTriangleLeaf triangleLeaf(std::byte* records, uint64_t first, uint32_t n) {
    return {records + kTriangleBytes * first, n};
}

// One active VkAabbPositionsKHR, as given (already floats: the tree bounds it exactly).
struct AabbRecord {
    float lower[3];  // minX, minY, minZ
    float upper[3];  // maxX, maxY, maxZ
    uint32_t geometryIndex;
    uint32_t primitiveIndex;
    uint32_t flags;
    uint32_t reserved[3];
};
// Same size as a triangle record, so the build-size formula holds for both kinds of bottom-level structure.
static_assert(sizeof(AabbRecord) == sizeof(TriangleRecord));

// [NV-LSS] Sphere and linear-swept-sphere record flags: bits 0-2 as for triangles, plus the end caps of an LSS.
constexpr uint32_t kSweptOpaque = kTriangleOpaque;
// Zero radius (LSS: both radii zero), kept only by ALLOW_UPDATE builds so that an update can give it a radius;
// also set by an invalid update. Never hit; re-decided by every refit.
constexpr uint32_t kSweptDegenerate = kTriangleDegenerate;
constexpr uint32_t kSweptNoDuplicateAnyHit = kTriangleNoDuplicateAnyHit;
constexpr uint32_t kLssCap0 = 0x10;  // the sphere at the first endpoint (u = 0) is a surface of the primitive
constexpr uint32_t kLssCap1 = 0x20;  // the sphere at the second endpoint (u = 1)

// One active sphere (VK_GEOMETRY_TYPE_SPHERES_NV): the decoded position (rounded to float) and radius.
struct SphereRecord {
    float center[3];
    float radius;
    uint32_t geometryIndex;
    uint32_t primitiveIndex;
    uint32_t flags;
    uint32_t reserved[5];
};
static_assert(sizeof(SphereRecord) == sizeof(TriangleRecord));

// One active linear swept sphere (VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV): endpoints and radii in application
// order, and which end caps the end-caps mode leaves on.
struct LssRecord {
    float p0[3];
    float r0;
    float p1[3];
    float r1;
    uint32_t geometryIndex;
    uint32_t primitiveIndex;
    uint32_t flags;
    uint32_t reserved;
};
static_assert(sizeof(LssRecord) == sizeof(TriangleRecord));

struct InstanceRecord {
    float objectToWorld[3][4];
    float worldToObject[3][4];
    uint32_t customIndexAndMask;  // bits 0-23 custom index, 24-31 mask (as in VkAccelerationStructureInstanceKHR)
    uint32_t sbtOffsetAndFlags;   // bits 0-23 SBT record offset, 24-31 VkGeometryInstanceFlagsKHR
    uint64_t reference;           // the VkAccelerationStructureKHR handle of the bottom-level structure
    uint32_t instanceId;          // index in the instance array given to the build
    uint32_t motionType;          // motion top level: VkAccelerationStructureMotionInstanceTypeNV (0 static); else 0
    uint32_t reserved[2];
};
static_assert(sizeof(InstanceRecord) == 128);

// [NV-motion] Records of structures built with VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV (buildFlags in the
// header tells them apart; traversal branches once per structure). See docs/FORMAT.md and format/motion.hpp.
//
// A motion top level stores one MotionInstanceRecord per active instance. `base` is an ordinary instance record:
// for a static motion instance its transforms are the instance's; for matrix and SRT motion they are the
// transform at time 0 and its inverse (informative), and `base.motionType` selects how `motion` interpolates:
//   MATRIX (1): motion[0..11] transformT0, motion[12..23] transformT1 (3x4 row-major), the rest zero
//   SRT (2):    motion[0..15] transformT0, motion[16..31] transformT1 (VkSRTDataNV order)
struct MotionInstanceRecord {
    InstanceRecord base;
    float motion[32];
};
static_assert(sizeof(MotionInstanceRecord) == 256);

// A motion bottom level of triangles stores MotionTriangleRecords: `base` holds the time-0 positions (flags has
// kTriangleMotion) and v1 the time-1 positions; traversal interpolates linearly.
constexpr uint32_t kTriangleMotion = 0x8;
struct MotionTriangleRecord {
    TriangleRecord base;
    float v1[3][3];
    uint32_t reserved[3];
};
static_assert(sizeof(MotionTriangleRecord) == 96);

inline const Header* header(const std::byte* base) { return reinterpret_cast<const Header*>(base); }
inline const GeometryDesc* geometries(const std::byte* base) {
    return reinterpret_cast<const GeometryDesc*>(base + header(base)->geometryOffset);
}
inline const Node* nodes(const std::byte* base) {
    return reinterpret_cast<const Node*>(base + header(base)->nodeOffset);
}
inline const std::byte* records(const std::byte* base) { return base + header(base)->recordOffset; }
inline const AabbRecord* aabbs(const std::byte* base) {
    return reinterpret_cast<const AabbRecord*>(base + header(base)->recordOffset);
}
inline const SphereRecord* spheres(const std::byte* base) {
    return reinterpret_cast<const SphereRecord*>(base + header(base)->recordOffset);
}
inline const LssRecord* lssRecords(const std::byte* base) {
    return reinterpret_cast<const LssRecord*>(base + header(base)->recordOffset);
}
inline const InstanceRecord* instances(const std::byte* base) {
    return reinterpret_cast<const InstanceRecord*>(base + header(base)->recordOffset);
}
inline const MotionInstanceRecord* motionInstances(const std::byte* base) {
    return reinterpret_cast<const MotionInstanceRecord*>(base + header(base)->recordOffset);
}
inline const MotionTriangleRecord* motionTriangles(const std::byte* base) {
    return reinterpret_cast<const MotionTriangleRecord*>(base + header(base)->recordOffset);
}

}  // namespace vkas::format

namespace vkas {

// Turns an instance's accelerationStructureReference into the block of the bottom-level structure it names, or
// nullptr when it names none. Supplied by the API layer, which owns the handles; builds, refits and traversal use it.
using BlasResolver = const std::byte* (*)(uint64_t reference);

}  // namespace vkas
