// The ray program of tests/conformance/diff_case.hpp, one invocation per ray. Compiled twice at build time: with
// VKAS_POSITION_FETCH defined (the device has rayTracingPositionFetch) and without (a module that declares the
// RayQueryPositionFetchKHR capability may not be used on a device without the feature).
#version 460
#extension GL_EXT_ray_query : require
#ifdef VKAS_POSITION_FETCH
#extension GL_EXT_spirv_intrinsics : require
#endif

layout(local_size_x = 64) in;

// std430 mirrors of diff::Ray (48 bytes) and diff::Result (608 bytes).
struct Ray {
    vec3 origin;
    float tMin;
    vec3 direction;
    float tMax;
    uint flags;
    uint cullMask;
    uint mode;
    uint reserved;
};

struct CandidateRecord {
    uint type;
    uint instanceId;
    uint geometryIndex;
    uint primitiveIndex;
};

const uint kMaxRecordedCandidates = 32u;
const uint kModeCount = 1u;

struct Result {
    uint committedType;
    uint instanceId;
    uint customIndex;
    uint sbtOffset;
    uint geometryIndex;
    uint primitiveIndex;
    uint frontFace;
    uint candidateCount;
    float t;
    float barycentrics[2];  // an array, not a vec2: std430 would align a vec2 to 8 bytes
    uint positionsValid;
    vec4 positions[3];
    CandidateRecord candidates[kMaxRecordedCandidates];
};

layout(set = 0, binding = 0) uniform accelerationStructureEXT tlas;
layout(std430, set = 0, binding = 1) readonly buffer Rays { Ray rays[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Results { Result results[]; };
// diff::ProceduralTables.
layout(std430, set = 0, binding = 3) readonly buffer InstanceBlas { uint instanceBlas[]; };
layout(std430, set = 0, binding = 4) readonly buffer BlasFirstGeometry { uint blasFirstGeometry[]; };
layout(std430, set = 0, binding = 5) readonly buffer BlasFlags { uint blasFlags[]; };
layout(std430, set = 0, binding = 6) readonly buffer GeometryFirstBox { uint geometryFirstBox[]; };
layout(std430, set = 0, binding = 7) readonly buffer Boxes { vec4 boxes[]; };  // per box: (min, 0), (max, 0)

layout(push_constant) uniform PushConstants { uint rayCount; } pc;

#ifdef VKAS_POSITION_FETCH
// OpRayQueryGetIntersectionTriangleVertexPositionsKHR (5340), capability RayQueryPositionFetchKHR (5391): glslang 12
// predates GL_EXT_ray_tracing_position_fetch. The Intersection operand must be a constant.
spirv_instruction(extensions = ["SPV_KHR_ray_tracing_position_fetch"], capabilities = [5391], id = 5340)
vec3[3] rayQueryFetchPositions(spirv_by_reference rayQueryEXT q, int committed);
#endif

bool confirmRule(uint instanceId, uint geometryIndex, uint primitiveIndex) {
    return (primitiveIndex * 3u + geometryIndex * 5u + instanceId * 7u) % 4u != 0u;
}

bool generateRule(uint instanceId, uint geometryIndex, uint primitiveIndex) {
    return (primitiveIndex + geometryIndex * 2u + instanceId) % 3u != 2u;
}

void main() {
    const uint id = gl_GlobalInvocationID.x;
    if (id >= pc.rayCount) return;
    const Ray ray = rays[id];

    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, ray.flags, ray.cullMask, ray.origin, ray.tMin, ray.direction, ray.tMax);
    uint count = 0u;
    while (rayQueryProceedEXT(q)) {
        const uint type = rayQueryGetIntersectionTypeEXT(q, false);
        const uint instanceId = uint(rayQueryGetIntersectionInstanceIdEXT(q, false));
        const uint geometryIndex = uint(rayQueryGetIntersectionGeometryIndexEXT(q, false));
        const uint primitiveIndex = uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, false));
        if (count < kMaxRecordedCandidates)
            results[id].candidates[count] = CandidateRecord(type, instanceId, geometryIndex, primitiveIndex);
        count++;
        if (ray.mode == kModeCount) continue;

        if (type == gl_RayQueryCandidateIntersectionTriangleEXT) {
            if (confirmRule(instanceId, geometryIndex, primitiveIndex)) rayQueryConfirmIntersectionEXT(q);
            continue;
        }
        // AABB: the slab test against the box from the tables, in float without contraction (precise), exactly as
        // the other side computes it.
        const uint box = geometryFirstBox[blasFirstGeometry[instanceBlas[instanceId]] + geometryIndex] + primitiveIndex;
        const vec3 boxMin = boxes[2u * box].xyz;
        const vec3 boxMax = boxes[2u * box + 1u].xyz;
        const vec3 o = rayQueryGetIntersectionObjectRayOriginEXT(q, false);
        const vec3 d = rayQueryGetIntersectionObjectRayDirectionEXT(q, false);
        precise const vec3 t0 = (boxMin - o) / d;
        precise const vec3 t1 = (boxMax - o) / d;
        precise const float tNear = max(max(min(t0.x, t1.x), min(t0.y, t1.y)), min(t0.z, t1.z));
        precise const float tFar = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z));
        precise const float tHit = max(tNear, ray.tMin);
        const float limit = rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionNoneEXT
                                ? ray.tMax
                                : rayQueryGetIntersectionTEXT(q, true);
        if (generateRule(instanceId, geometryIndex, primitiveIndex) && tHit <= tFar && tHit <= limit)
            rayQueryGenerateIntersectionEXT(q, tHit);
    }

    // Undefined fields are written as 0, recorded candidates beyond count too.
    for (uint i = count; i < kMaxRecordedCandidates; ++i) results[id].candidates[i] = CandidateRecord(0u, 0u, 0u, 0u);
    results[id].candidateCount = count;
    const uint committedType = rayQueryGetIntersectionTypeEXT(q, true);
    results[id].committedType = committedType;
    uint instanceId = 0u, customIndex = 0u, sbtOffset = 0u, geometryIndex = 0u, primitiveIndex = 0u, frontFace = 0u;
    float t = 0.0;
    vec2 barycentrics = vec2(0.0);
    uint positionsValid = 0u;
    vec3 positions[3] = vec3[3](vec3(0.0), vec3(0.0), vec3(0.0));
    if (committedType != gl_RayQueryCommittedIntersectionNoneEXT) {
        instanceId = uint(rayQueryGetIntersectionInstanceIdEXT(q, true));
        customIndex = uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, true));
        sbtOffset = rayQueryGetIntersectionInstanceShaderBindingTableRecordOffsetEXT(q, true);
        geometryIndex = uint(rayQueryGetIntersectionGeometryIndexEXT(q, true));
        primitiveIndex = uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true));
        t = rayQueryGetIntersectionTEXT(q, true);
    }
    if (committedType == gl_RayQueryCommittedIntersectionTriangleEXT) {
        frontFace = rayQueryGetIntersectionFrontFaceEXT(q, true) ? 1u : 0u;
        barycentrics = rayQueryGetIntersectionBarycentricsEXT(q, true);
#ifdef VKAS_POSITION_FETCH
        if ((blasFlags[instanceBlas[instanceId]] & 1u) != 0u) {
            positions = rayQueryFetchPositions(q, 1);
            positionsValid = 1u;
        }
#endif
    }
    results[id].instanceId = instanceId;
    results[id].customIndex = customIndex;
    results[id].sbtOffset = sbtOffset;
    results[id].geometryIndex = geometryIndex;
    results[id].primitiveIndex = primitiveIndex;
    results[id].frontFace = frontFace;
    results[id].t = t;
    results[id].barycentrics[0] = barycentrics.x;
    results[id].barycentrics[1] = barycentrics.y;
    results[id].positionsValid = positionsValid;
    for (int i = 0; i < 3; ++i) results[id].positions[i] = vec4(positions[i], 0.0);
}
