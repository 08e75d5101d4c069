/*
 * Package consumer: a C11 program built against an installed vkas (find_package(vkas) or pkg-config vkas).
 * It proves that <vkas/vkas.h> is usable from C and that the installed library works: it builds a bottom-level
 * structure (a quad of two indexed triangles), a top-level structure with two instances of it, and traces a ray
 * with a host ray query and with vkasTraceRays. Exit status 0 when every check passes.
 */
#include <stdio.h>
#include <string.h>

#include <vkas/vkas.h>

static int failures = 0;
#define CHECK(cond)                                                             \
    do {                                                                        \
        if (!(cond)) {                                                          \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            ++failures;                                                         \
        }                                                                       \
    } while (0)
#define CHECK_VK(call)                                                          \
    do {                                                                        \
        VkResult r_ = (call);                                                   \
        if (r_ != VK_SUCCESS) {                                                 \
            fprintf(stderr, "%s:%d: %s returned %d\n", __FILE__, __LINE__, #call, (int)r_); \
            return 1;                                                           \
        }                                                                       \
    } while (0)

static PFN_vkCreateBuffer pCreateBuffer;
static PFN_vkDestroyBuffer pDestroyBuffer;
static PFN_vkGetBufferMemoryRequirements pGetBufferMemoryRequirements;
static PFN_vkAllocateMemory pAllocateMemory;
static PFN_vkFreeMemory pFreeMemory;
static PFN_vkBindBufferMemory pBindBufferMemory;
static PFN_vkMapMemory pMapMemory;
static PFN_vkGetAccelerationStructureBuildSizesKHR pGetBuildSizes;
static PFN_vkCreateAccelerationStructureKHR pCreateAS;
static PFN_vkDestroyAccelerationStructureKHR pDestroyAS;
static PFN_vkBuildAccelerationStructuresKHR pBuildAS;

static int near(float a, float b) { return a - b < 1e-5f && b - a < 1e-5f; }

typedef struct HostBuffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
    void* data;
} HostBuffer;

static VkResult create_buffer(VkDevice device, VkDeviceSize size, VkBufferUsageFlags usage, HostBuffer* out) {
    VkBufferCreateInfo bci;
    memset(&bci, 0, sizeof bci);
    bci.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
    bci.size = size;
    bci.usage = usage;
    VkResult r = pCreateBuffer(device, &bci, NULL, &out->buffer);
    if (r != VK_SUCCESS) return r;
    VkMemoryRequirements req;
    pGetBufferMemoryRequirements(device, out->buffer, &req);
    VkMemoryAllocateInfo mai;
    memset(&mai, 0, sizeof mai);
    mai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    mai.allocationSize = req.size;
    mai.memoryTypeIndex = 0; /* host memory */
    if ((r = pAllocateMemory(device, &mai, NULL, &out->memory)) != VK_SUCCESS) return r;
    if ((r = pBindBufferMemory(device, out->buffer, out->memory, 0)) != VK_SUCCESS) return r;
    return pMapMemory(device, out->memory, 0, VK_WHOLE_SIZE, 0, &out->data);
}

static void destroy_buffer(VkDevice device, HostBuffer* b) {
    pDestroyBuffer(device, b->buffer, NULL);
    pFreeMemory(device, b->memory, NULL);
}

/* Sizes query, storage buffer, creation and a host build of one structure. */
static VkResult build(VkDevice device, VkAccelerationStructureBuildGeometryInfoKHR* info, uint32_t primitiveCount,
                      const VkAccelerationStructureBuildRangeInfoKHR* range, HostBuffer* storage,
                      VkAccelerationStructureKHR* as) {
    VkAccelerationStructureBuildSizesInfoKHR sizes;
    memset(&sizes, 0, sizeof sizes);
    sizes.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_SIZES_INFO_KHR;
    pGetBuildSizes(device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, info, &primitiveCount, &sizes);
    VkResult r = create_buffer(device, sizes.accelerationStructureSize,
                               VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR, storage);
    if (r != VK_SUCCESS) return r;
    HostBuffer scratch;
    if ((r = create_buffer(device, sizes.buildScratchSize ? sizes.buildScratchSize : 1,
                           VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, &scratch)) != VK_SUCCESS)
        return r;
    VkAccelerationStructureCreateInfoKHR aci;
    memset(&aci, 0, sizeof aci);
    aci.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR;
    aci.buffer = storage->buffer;
    aci.size = sizes.accelerationStructureSize;
    aci.type = info->type;
    if ((r = pCreateAS(device, &aci, NULL, as)) != VK_SUCCESS) return r;
    info->dstAccelerationStructure = *as;
    info->scratchData.hostAddress = scratch.data;
    r = pBuildAS(device, VK_NULL_HANDLE, 1, info, &range);
    destroy_buffer(device, &scratch);
    return r;
}

int main(void) {
    VkDevice device;
    CHECK_VK(vkasCreateDevice(NULL, &device));
#define LOAD(var, name) CHECK((var = (PFN_##name)vkasGetDeviceProcAddr(device, #name)) != NULL)
    LOAD(pCreateBuffer, vkCreateBuffer);
    LOAD(pDestroyBuffer, vkDestroyBuffer);
    LOAD(pGetBufferMemoryRequirements, vkGetBufferMemoryRequirements);
    LOAD(pAllocateMemory, vkAllocateMemory);
    LOAD(pFreeMemory, vkFreeMemory);
    LOAD(pBindBufferMemory, vkBindBufferMemory);
    LOAD(pMapMemory, vkMapMemory);
    LOAD(pGetBuildSizes, vkGetAccelerationStructureBuildSizesKHR);
    LOAD(pCreateAS, vkCreateAccelerationStructureKHR);
    LOAD(pDestroyAS, vkDestroyAccelerationStructureKHR);
    LOAD(pBuildAS, vkBuildAccelerationStructuresKHR);
    CHECK(vkasGetDeviceProcAddr(device, "vkNoSuchCommand") == NULL);
    if (failures) return 1;

    /* Bottom level: the quad [-1, 1]^2 at z = 0, two UINT16-indexed triangles, not opaque. */
    static const float vertices[4][3] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    static const uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
    VkAccelerationStructureGeometryKHR geometry;
    memset(&geometry, 0, sizeof geometry);
    geometry.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR;
    geometry.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
    geometry.geometry.triangles.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
    geometry.geometry.triangles.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
    geometry.geometry.triangles.vertexData.hostAddress = vertices;
    geometry.geometry.triangles.vertexStride = sizeof vertices[0];
    geometry.geometry.triangles.maxVertex = 3;
    geometry.geometry.triangles.indexType = VK_INDEX_TYPE_UINT16;
    geometry.geometry.triangles.indexData.hostAddress = indices;
    VkAccelerationStructureBuildGeometryInfoKHR info;
    memset(&info, 0, sizeof info);
    info.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_BUILD_GEOMETRY_INFO_KHR;
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    info.flags = VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR;
    info.mode = VK_BUILD_ACCELERATION_STRUCTURE_MODE_BUILD_KHR;
    info.geometryCount = 1;
    info.pGeometries = &geometry;
    VkAccelerationStructureBuildRangeInfoKHR range = {2, 0, 0, 0};
    HostBuffer blasStorage;
    VkAccelerationStructureKHR blas;
    CHECK_VK(build(device, &info, 2, &range, &blasStorage, &blas));

    /* Top level: the quad at z = -5 (custom index 7) and at z = -10 (custom index 9). */
    VkAccelerationStructureInstanceKHR instances[2];
    memset(instances, 0, sizeof instances);
    for (int i = 0; i < 2; ++i) {
        instances[i].transform.matrix[0][0] = instances[i].transform.matrix[1][1] = 1.0f;
        instances[i].transform.matrix[2][2] = 1.0f;
        instances[i].transform.matrix[2][3] = i == 0 ? -5.0f : -10.0f;
        instances[i].instanceCustomIndex = i == 0 ? 7 : 9;
        instances[i].mask = 0xFF;
        instances[i].accelerationStructureReference = (uint64_t)(uintptr_t)blas; /* host builds: the handle */
    }
    geometry.geometryType = VK_GEOMETRY_TYPE_INSTANCES_KHR;
    memset(&geometry.geometry, 0, sizeof geometry.geometry);
    geometry.geometry.instances.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_INSTANCES_DATA_KHR;
    geometry.geometry.instances.data.hostAddress = instances;
    info.type = VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR;
    range.primitiveCount = 2;
    HostBuffer tlasStorage;
    VkAccelerationStructureKHR tlas;
    CHECK_VK(build(device, &info, 2, &range, &tlasStorage, &tlas));

    /* A ray query down -z from (0.25, 0.5, 0): confirms each non-opaque candidate, commits the nearest. */
    const float origin[3] = {0.25f, 0.5f, 0.0f}, direction[3] = {0.0f, 0.0f, -1.0f};
    VkasRayQuery query;
    vkasRayQueryInitialize(&query, tlas, VKAS_RAY_FLAG_NONE, 0xFF, origin, 0.0f, direction, 100.0f);
    int candidates = 0;
    while (vkasRayQueryProceed(&query)) {
        if (vkasRayQueryGetIntersectionType(&query, VK_FALSE) == VKAS_CANDIDATE_INTERSECTION_TRIANGLE) {
            ++candidates;
            vkasRayQueryConfirmIntersection(&query);
        }
    }
    CHECK(candidates >= 1);
    CHECK(vkasRayQueryGetIntersectionType(&query, VK_TRUE) == VKAS_COMMITTED_INTERSECTION_TRIANGLE);
    CHECK(near(vkasRayQueryGetIntersectionT(&query, VK_TRUE), 5.0f));
    CHECK(vkasRayQueryGetIntersectionInstanceId(&query, VK_TRUE) == 0);
    CHECK(vkasRayQueryGetIntersectionInstanceCustomIndex(&query, VK_TRUE) == 7);
    CHECK(vkasRayQueryGetIntersectionPrimitiveIndex(&query, VK_TRUE) == 1); /* (0.25, 0.5) lies in triangle 1 */

    /* The same ray, and one that misses, through the batch call. */
    VkasRay rays[2] = {{{0.25f, 0.5f, 0.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 100.0f},
                       {{3.0f, 0.0f, 0.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 100.0f}};
    VkasHit hits[2];
    CHECK_VK(vkasTraceRays(device, tlas, VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_RAY_FLAG_NONE, 0xFF, 2, rays, hits));
    CHECK(hits[0].type == VKAS_COMMITTED_INTERSECTION_TRIANGLE && near(hits[0].t, 5.0f) && hits[0].instanceCustomIndex == 7);
    CHECK(hits[1].type == VKAS_COMMITTED_INTERSECTION_NONE);

    /* A null acceleration structure: every ray misses. */
    vkasRayQueryInitialize(&query, VK_NULL_HANDLE, VKAS_RAY_FLAG_NONE, 0xFF, origin, 0.0f, direction, 100.0f);
    CHECK(!vkasRayQueryProceed(&query));
    CHECK(vkasRayQueryGetIntersectionType(&query, VK_TRUE) == VKAS_COMMITTED_INTERSECTION_NONE);

    pDestroyAS(device, tlas, NULL);
    pDestroyAS(device, blas, NULL);
    destroy_buffer(device, &tlasStorage);
    destroy_buffer(device, &blasStorage);
    vkasDestroyDevice(device);
    if (failures) {
        fprintf(stderr, "package consumer: %d check(s) failed\n", failures);
        return 1;
    }
    printf("package consumer: vkas %d.%d.%d works from C\n", VKAS_VERSION_MAJOR, VKAS_VERSION_MINOR,
           VKAS_VERSION_PATCH);
    return 0;
}
