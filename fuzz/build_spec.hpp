// The input layout of fuzz_build: a fixed 88-byte BuildSpec (every field is raw bytes; the harness reduces them to
// bounded parameters), then a payload that fills the geometry data (vertices, indices, transforms, AABBs, radii,
// instance records), cycled when short. make_corpus writes inputs in the same layout.
#pragma once

#include <cstdint>

namespace fz {

// GeomSpec::fix bits.
enum : uint8_t {
    kAutoMaxVertex = 1 << 0,  // maxVertex = exactly what the indices / range read
    kAutoStride = 1 << 1,     // strides = the element size
    kAlign = 1 << 2,          // primitiveOffset and transformOffset rounded down to a multiple of 16
    kNiceData = 1 << 3,       // finite coordinates, ordered AABBs, positive radii, indices in range, real BLASes
    kNullData = 1 << 4,       // vertex / AABB / instance data pointer NULL
    kFlipIndexPointer = 1 << 5,  // index pointer NULL when indexed, set when not (one NULL instance pointer)
    kBadSType = 1 << 6,       // wrong sType in the geometry's data structure
    kBadGeometry = 1 << 7,    // spheres / LSS: no data structure in pNext; others: wrong geometry sType
};

// GeomSpec::motion bits. Triangles (any build; in a build without the motion flag validation reports them):
enum : uint8_t {
    kMotionTriangles = 1 << 0,      // chain a VkAccelerationStructureGeometryMotionTrianglesDataNV (time-1 vertices)
    kMotionNullVertices = 1 << 1,   // its vertexData NULL
    kMotionBadSType = 1 << 2,       // its sType wrong (an unknown structure in the triangles' pNext)
    kMotionNearVertices = 1 << 3,   // with kNiceData: time-1 vertices near the time-0 ones (else payload / nice floats)
};
// Instances of a motion build (VkAccelerationStructureMotionInstanceNV, 160-byte stride, or typed pointers):
enum : uint8_t {
    kMotionRawType = 1 << 0,        // instance types are raw payload (array: a u32; pointers: the low 4 bits), so
                                    // invalid types occur; else a payload byte % 3
    kMotionFlags = 1 << 1,          // array mode: the motion instance's flags word is raw payload (else 0)
    kMotionNonFinite = 1 << 2,      // one transform float of each instance NaN, +inf or -inf (after kNiceData)
    kMotionOneType = 1 << 3,        // every instance of type (motion >> 4) % 3 (0 static, 1 matrix, 2 SRT)
};

#pragma pack(push, 1)
struct GeomSpec {              // 24 bytes
    uint8_t format;            // vertex format: a table of the 16 supported formats and 4 unsupported ones
    uint8_t indexType;         // % 4: NONE, UINT16, UINT32, an invalid value
    uint8_t flags;             // geometry flags: bit 0 OPAQUE, bit 1 NO_DUPLICATE_ANY_HIT, bit 2 an unknown bit
    uint8_t fix;               // k* bits above
    uint16_t count;            // primitiveCount % 300 (instances % 64)
    uint16_t primitiveOffset;  // raw
    uint16_t firstVertex;      // % 512
    uint16_t maxVertex;        // % 2048
    uint8_t stride;            // vertex stride (triangles, spheres, LSS) or AABB stride, raw
    uint8_t transform;         // triangles: 0 no transform, else transformOffset = transform - 1
    uint8_t radius;            // bits 0-1 radius format (R32, R16, an unsupported one, R32); bits 2-7 radiusStride
    uint8_t lss;               // bit 0 SUCCESSIVE, bit 1 CHAINED, bit 2 invalid modes, bits 3-4 indexStride in indices
    uint8_t instances;         // bit 0 arrayOfPointers
    int8_t maxCountDelta;      // with BuildSpec::dstSize mode 3: pMaxPrimitiveCounts = count + delta
    uint16_t indexSpan;        // spheres / LSS indices address 1 + indexSpan % 256 vertices
    uint8_t motion;            // [NV-motion] kMotion* bits below (triangles and instances)
    uint8_t pad[3];
};
struct BuildSpec {             // 16 + 3 * 24 = 88 bytes
    uint8_t kind;              // % 5: triangles, AABBs, instances (top level), spheres, LSS
    uint8_t geometryCount;     // bottom level % 4; top level 1 unless bit 7 (then % 4); bit 6: geometry 1 of another type
    uint8_t buildFlags;        // bits 0-4 ALLOW_UPDATE .. LOW_MEMORY, bit 5 ALLOW_DATA_ACCESS, bit 6 an unknown bit
    uint8_t mode;              // bit 0 UPDATE, 1 in place, 2 deferred, 3 ppGeometries, 4 two infos, 5 dst of the other
                               // type, 6 info type GENERIC, 7 an invalid mode value
    uint8_t dstSize;           // bits 0-1: 0 the size query's, 1 256 more, 2 (bits 2-7) + 1 bytes less, 3 query with
                               // pMaxPrimitiveCounts = count + maxCountDelta
    uint8_t scratch;           // bit 0 NULL, bit 1 inside the dst's memory, bits 2-7 offset of the scratch pointer
    uint8_t asOffset;          // bit 0: the structure at offset 256 of its buffer
    uint8_t update;            // what an update changes: bit 0 counts + 1, 1 new data, 2 build flags, 3 maxVertex,
                               // 4 vertex format, 5 transform presence, 6 geometry flags, 7 index type
    uint8_t misc;              // bit 0 bad info sType, 1 NULL range pointer, 2 both geometry pointers, 3 neither,
                               // 4 infoCount 0, 5 garbage src handle, 6 garbage dst handle
    uint8_t motion;            // [NV-motion] bit 0 a motion build (VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV, the
                               // structures created with VK_ACCELERATION_STRUCTURE_CREATE_MOTION_BIT_NV and, top
                               // level, a VkAccelerationStructureMotionInfoNV), bit 1 the destination's create flag
                               // the other way (VUID 04927 / 04928), bit 2 VkAccelerationStructureMotionInfoNV::
                               // maxInstances 0 (only a hint)
    uint8_t pad[6];
    GeomSpec g[3];
};
#pragma pack(pop)
static_assert(sizeof(GeomSpec) == 24);
static_assert(sizeof(BuildSpec) == 88);

}  // namespace fz
