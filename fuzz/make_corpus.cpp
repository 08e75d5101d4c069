// Writes the seed corpora of the fuzz targets: `vkas_fuzz_make_corpus <dir>` fills <dir>/deserialize (serialized
// structures of every kind, motion ones and one with opacity micromaps included, and small ones of one primitive
// each, all written by the public serialize command, handle arrays written as fuzz_deserialize's tokens) and <dir>/build (BuildSpec inputs
// that decode to valid builds of every geometry type and mode). fuzz/corpus/ holds its output.
#include <cstdio>
#include <string>
#include <sys/stat.h>

#include "build_spec.hpp"
#include "fuzz_common.hpp"

namespace {

using fz::BuildSpec;
using fz::Device;
using fz::Structure;

void writeFile(const std::string& path, const uint8_t* data, size_t size) {
    FILE* f = std::fopen(path.c_str(), "wb");
    FZ_CHECK(f != nullptr, "cannot write %s", path.c_str());
    FZ_CHECK(std::fwrite(data, 1, size, f) == size, "short write to %s", path.c_str());
    std::fclose(f);
    std::printf("  %s (%zu bytes)\n", path.c_str(), size);
}

// Serializes `s` and writes it with its handle array as tokens (fuzz_deserialize.cpp).
void writeBlob(Device& d, const Structure& s, const std::string& path) {
    VkDeviceSize size = 0;
    FZ_CHECK(d.vkWriteAccelerationStructuresPropertiesKHR(d.device, 1, &s.handle,
                                                          VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR,
                                                          sizeof size, &size, sizeof size) == VK_SUCCESS,
             "size query");
    fz::Region blob(size);
    VkCopyAccelerationStructureToMemoryInfoKHR ci{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_TO_MEMORY_INFO_KHR};
    ci.src = s.handle;
    ci.dst.hostAddress = blob.data;
    ci.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_SERIALIZE_KHR;
    FZ_CHECK(d.vkCopyAccelerationStructureToMemoryKHR(d.device, VK_NULL_HANDLE, &ci) == VK_SUCCESS, "serialize");
    uint64_t n;
    std::memcpy(&n, blob.data + 48, 8);
    const uint64_t tokens[][2] = {{uint64_t(d.blasTriangles.handle), 1}, {uint64_t(d.blasAabbs.handle), 3},
                                  {uint64_t(d.blasSpheres.handle), 4},   {uint64_t(d.blasLss.handle), 5},
                                  {uint64_t(d.tlas.handle), 6},          {uint64_t(d.blasMotion.handle), 12},
                                  {uint64_t(d.tlasMotion.handle), 13}};
    for (uint64_t k = 0; k < n; ++k) {
        uint64_t v;
        std::memcpy(&v, blob.data + 56 + 8 * k, 8);
        uint64_t token = v == 0 ? 0 : 14;  // 14: an unknown value
        for (const auto& t : tokens)
            if (t[0] == v) token = t[1];
        std::memcpy(blob.data + 56 + 8 * k, &token, 8);
    }
    writeFile(path, blob.data, blob.size);
}

void writeSpec(const std::string& path, const BuildSpec& spec, size_t payloadSize, uint64_t seed) {
    std::vector<uint8_t> bytes(sizeof spec + payloadSize);
    std::memcpy(bytes.data(), &spec, sizeof spec);
    fz::Rng rng(seed);
    for (size_t i = sizeof spec; i < bytes.size(); ++i) bytes[i] = uint8_t(rng.next());
    writeFile(path, bytes.data(), bytes.size());
}

BuildSpec validSpec(uint32_t kind, uint16_t count) {
    BuildSpec s{};
    s.kind = uint8_t(kind);
    s.geometryCount = 1;
    for (auto& g : s.g) {
        g.format = 0;  // R32G32B32_SFLOAT
        g.indexType = 2;  // UINT32
        g.fix = fz::kAutoMaxVertex | fz::kAutoStride | fz::kAlign | fz::kNiceData;
        g.count = count;
        g.indexSpan = 40;
    }
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s <corpus dir>\n", argv[0]);
        return 2;
    }
    const std::string dir = argv[1];
    ::mkdir(dir.c_str(), 0755);
    ::mkdir((dir + "/deserialize").c_str(), 0755);
    ::mkdir((dir + "/build").c_str(), 0755);
    Device& d = fz::validatingDevice();

    // Serialized structures: each real structure of the harness, and a larger mesh (a deeper tree).
    writeBlob(d, d.blasTriangles, dir + "/deserialize/blas_triangles.bin");
    writeBlob(d, d.blasAabbs, dir + "/deserialize/blas_aabbs.bin");
    writeBlob(d, d.blasSpheres, dir + "/deserialize/blas_spheres.bin");
    writeBlob(d, d.blasLss, dir + "/deserialize/blas_lss.bin");
    writeBlob(d, d.tlas, dir + "/deserialize/tlas.bin");
    {
        fz::Rng rng(7);
        std::vector<float> v(3 * 3 * 120);
        for (size_t i = 0; i < v.size(); i += 9) {
            const float c[3] = {rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5)};
            for (int k = 0; k < 9; ++k) v[i + k] = c[k % 3] + rng.uniform(-0.4f, 0.4f);
        }
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
        g.flags = VK_GEOMETRY_OPAQUE_BIT_KHR;
        auto& t = g.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = v.data();
        t.vertexStride = 12;
        t.maxVertex = uint32_t(v.size() / 3 - 1);
        t.indexType = VK_INDEX_TYPE_NONE_KHR;
        Structure mesh = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, uint32_t(v.size() / 9),
                                       VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR);
        writeBlob(d, mesh, dir + "/deserialize/blas_mesh120.bin");
        d.destroyStructure(mesh);
        // The same count of larger, overlapping triangles built with PREFER_FAST_TRACE: spatial splits cut some, so
        // the blob has fragment records and a fragment section (docs/FORMAT.md, "Fragments").
        for (size_t i = 0; i < v.size(); i += 9) {
            const float c[3] = {rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-5, 5)};
            for (int k = 0; k < 9; ++k) v[i + k] = c[k % 3] + rng.uniform(-3.0f, 3.0f);
        }
        Structure cut = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, uint32_t(v.size() / 9),
                                      VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR);
        writeBlob(d, cut, dir + "/deserialize/blas_fragments120.bin");
        d.destroyStructure(cut);
    }
    {
        // A bottom level that uses an opacity micromap (VK_EXT_opacity_micromap): its blob holds the opacity section
        // (docs/FORMAT.md). Two micromap triangles, a 4-state one of level 2 and a 2-state one of level 1; four
        // triangles with 16-bit micromap indices 0, 1, the special index -2 (fully opaque) and 1 again.
#define FZ_LOAD(name) const auto name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(d.device, #name));
        FZ_LOAD(vkCreateBuffer)
        FZ_LOAD(vkDestroyBuffer)
        FZ_LOAD(vkAllocateMemory)
        FZ_LOAD(vkFreeMemory)
        FZ_LOAD(vkBindBufferMemory)
        FZ_LOAD(vkCreateMicromapEXT)
        FZ_LOAD(vkDestroyMicromapEXT)
        FZ_LOAD(vkGetMicromapBuildSizesEXT)
        FZ_LOAD(vkBuildMicromapsEXT)
#undef FZ_LOAD
        const uint8_t states[] = {0x1B, 0xE4, 0x6C, 0x39,  // 16 2-bit states of triangle 0 (level 2)
                                  0x09};                   // 4 1-bit states of triangle 1 (level 1)
        const VkMicromapTriangleEXT triangles[2] = {{0, 2, VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT},
                                                    {4, 1, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT}};
        const VkMicromapUsageEXT usage[2] = {{1, 2, VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT},
                                             {1, 1, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT}};
        VkMicromapBuildInfoEXT mb{VK_STRUCTURE_TYPE_MICROMAP_BUILD_INFO_EXT};
        mb.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        mb.mode = VK_BUILD_MICROMAP_MODE_BUILD_EXT;
        mb.usageCountsCount = 2;
        mb.pUsageCounts = usage;
        mb.data.hostAddress = states;
        mb.triangleArray.hostAddress = triangles;
        mb.triangleArrayStride = sizeof(VkMicromapTriangleEXT);
        VkMicromapBuildSizesInfoEXT sizes{VK_STRUCTURE_TYPE_MICROMAP_BUILD_SIZES_INFO_EXT};
        vkGetMicromapBuildSizesEXT(d.device, VK_ACCELERATION_STRUCTURE_BUILD_TYPE_HOST_KHR, &mb, &sizes);
        VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        bi.size = sizes.micromapSize;
        bi.usage = VK_BUFFER_USAGE_MICROMAP_STORAGE_BIT_EXT;
        VkBuffer buffer = VK_NULL_HANDLE;
        FZ_CHECK(vkCreateBuffer(d.device, &bi, nullptr, &buffer) == VK_SUCCESS, "micromap buffer");
        VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, nullptr, bi.size, 0};
        VkDeviceMemory memory = VK_NULL_HANDLE;
        FZ_CHECK(vkAllocateMemory(d.device, &ai, nullptr, &memory) == VK_SUCCESS, "micromap memory");
        FZ_CHECK(vkBindBufferMemory(d.device, buffer, memory, 0) == VK_SUCCESS, "micromap bind");
        VkMicromapCreateInfoEXT mc{VK_STRUCTURE_TYPE_MICROMAP_CREATE_INFO_EXT};
        mc.buffer = buffer;
        mc.size = sizes.micromapSize;
        mc.type = VK_MICROMAP_TYPE_OPACITY_MICROMAP_EXT;
        VkMicromapEXT micromap = VK_NULL_HANDLE;
        FZ_CHECK(vkCreateMicromapEXT(d.device, &mc, nullptr, &micromap) == VK_SUCCESS, "create micromap");
        fz::Region scratch(size_t(sizes.buildScratchSize) + 16);
        mb.dstMicromap = micromap;
        mb.scratchData.hostAddress = scratch.data;
        FZ_CHECK(vkBuildMicromapsEXT(d.device, VK_NULL_HANDLE, 1, &mb) == VK_SUCCESS, "build micromap");

        const float v[4][9] = {{-1, -1, 0, 1, -1, 0, 0, 1, 0},
                               {-1, -1, 1, 1, -1, 1, 0, 1, 1},
                               {-1, -1, 2, 1, -1, 2, 0, 1, 2},
                               {-1, -1, 3, 1, -1, 3, 0, 1, 3}};
        const uint16_t indices[4] = {0, 1, uint16_t(VK_OPACITY_MICROMAP_SPECIAL_INDEX_FULLY_OPAQUE_EXT), 1};
        const VkMicromapUsageEXT blasUsage[2] = {{1, 2, VK_OPACITY_MICROMAP_FORMAT_4_STATE_EXT},
                                                 {2, 1, VK_OPACITY_MICROMAP_FORMAT_2_STATE_EXT}};
        VkAccelerationStructureTrianglesOpacityMicromapEXT omm{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_TRIANGLES_OPACITY_MICROMAP_EXT};
        omm.indexType = VK_INDEX_TYPE_UINT16;
        omm.indexBuffer.hostAddress = indices;
        omm.indexStride = sizeof(uint16_t);
        omm.usageCountsCount = 2;
        omm.pUsageCounts = blasUsage;
        omm.micromap = micromap;
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
        auto& t = g.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.pNext = &omm;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = v;
        t.vertexStride = 12;
        t.maxVertex = 11;
        t.indexType = VK_INDEX_TYPE_NONE_KHR;
        Structure s1 = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 4,
                                     VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_OPACITY_MICROMAP_UPDATE_EXT);
        writeBlob(d, s1, dir + "/deserialize/blas_opacity_micromap.bin");
        d.destroyStructure(s1);
        vkDestroyMicromapEXT(d.device, micromap, nullptr);
        vkFreeMemory(d.device, memory, nullptr);
        vkDestroyBuffer(d.device, buffer, nullptr);
    }

    // [NV-motion] The motion structures of the harness.
    writeBlob(d, d.blasMotion, dir + "/deserialize/blas_motion_triangles.bin");
    writeBlob(d, d.tlasMotion, dir + "/deserialize/tlas_motion.bin");
    // Small blobs of every geometry type: one primitive (or instance) each.
    {
        const float tri[9] = {-1, -1, 0, 1, -1, 0.5f, 0, 1, 0.25f};
        const float tri1[9] = {-1, -1, 1, 1, -0.5f, 0.5f, 0.5f, 1, 0};
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_TRIANGLES_KHR;
        auto& t = g.geometry.triangles;
        t.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_TRIANGLES_DATA_KHR;
        t.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        t.vertexData.hostAddress = tri;
        t.vertexStride = 12;
        t.maxVertex = 2;
        t.indexType = VK_INDEX_TYPE_NONE_KHR;
        Structure s1 = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 1);
        writeBlob(d, s1, dir + "/deserialize/small_triangle.bin");
        d.destroyStructure(s1);
        VkAccelerationStructureGeometryMotionTrianglesDataNV m{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_MOTION_TRIANGLES_DATA_NV};
        m.vertexData.hostAddress = tri1;
        t.pNext = &m;
        s1 = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 1,
                           VK_BUILD_ACCELERATION_STRUCTURE_MOTION_BIT_NV);
        writeBlob(d, s1, dir + "/deserialize/small_motion_triangle.bin");
        d.destroyStructure(s1);
    }
    {
        const VkAabbPositionsKHR box = {-0.5f, -0.5f, -0.5f, 0.5f, 0.25f, 0.75f};
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.geometryType = VK_GEOMETRY_TYPE_AABBS_KHR;
        g.geometry.aabbs.sType = VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_AABBS_DATA_KHR;
        g.geometry.aabbs.data.hostAddress = &box;
        g.geometry.aabbs.stride = sizeof box;
        Structure s1 = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 1);
        writeBlob(d, s1, dir + "/deserialize/small_aabb.bin");
        d.destroyStructure(s1);
    }
    {
        const float centers[2][3] = {{-0.5f, 0, 0}, {0.5f, 0.25f, 0}};
        const float radii[2] = {0.3f, 0.2f};
        VkAccelerationStructureGeometrySpheresDataNV sp{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_SPHERES_DATA_NV};
        sp.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        sp.vertexData.hostAddress = centers;
        sp.vertexStride = 12;
        sp.radiusFormat = VK_FORMAT_R32_SFLOAT;
        sp.radiusData.hostAddress = radii;
        sp.radiusStride = 4;
        sp.indexType = VK_INDEX_TYPE_NONE_KHR;
        VkAccelerationStructureGeometryKHR g{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_KHR};
        g.pNext = &sp;
        g.geometryType = VK_GEOMETRY_TYPE_SPHERES_NV;
        Structure s1 = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 1);
        writeBlob(d, s1, dir + "/deserialize/small_sphere.bin");
        d.destroyStructure(s1);
        VkAccelerationStructureGeometryLinearSweptSpheresDataNV l{
            VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_GEOMETRY_LINEAR_SWEPT_SPHERES_DATA_NV};
        l.vertexFormat = VK_FORMAT_R32G32B32_SFLOAT;
        l.vertexData.hostAddress = centers;
        l.vertexStride = 12;
        l.radiusFormat = VK_FORMAT_R32_SFLOAT;
        l.radiusData.hostAddress = radii;
        l.radiusStride = 4;
        l.indexType = VK_INDEX_TYPE_NONE_KHR;
        l.indexingMode = VK_RAY_TRACING_LSS_INDEXING_MODE_LIST_NV;
        l.endCapsMode = VK_RAY_TRACING_LSS_PRIMITIVE_END_CAPS_MODE_NONE_NV;
        g.pNext = &l;
        g.geometryType = VK_GEOMETRY_TYPE_LINEAR_SWEPT_SPHERES_NV;
        s1 = d.buildSimple(VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, g, 1);
        writeBlob(d, s1, dir + "/deserialize/small_lss.bin");
        d.destroyStructure(s1);
    }
    {
        // Top levels of one instance: static, and motion of each type (the references become tokens).
        Structure s1 = d.buildSingleInstanceTlas(d.blasTriangles);
        writeBlob(d, s1, dir + "/deserialize/small_tlas.bin");
        d.destroyStructure(s1);
        const char* motionNames[3] = {"static", "matrix", "srt"};
        const Structure* refs[3] = {&d.blasAabbs, &d.blasMotion, &d.blasSpheres};
        for (int type = 0; type < 3; ++type) {
            s1 = d.buildSingleInstanceTlas(*refs[type], 0, type);
            writeBlob(d, s1, dir + "/deserialize/small_tlas_motion_" + motionNames[type] + ".bin");
            d.destroyStructure(s1);
        }
    }

    // Build inputs: valid builds of each geometry type, then modes.
    const char* names[5] = {"triangles", "aabbs", "instances", "spheres", "lss"};
    for (uint32_t kind = 0; kind < 5; ++kind)
        writeSpec(dir + "/build/" + names[kind] + ".bin", validSpec(kind, kind == 2 ? 6 : 24), 512, kind);
    BuildSpec s = validSpec(0, 40);
    s.g[0].indexType = 1;   // UINT16
    s.g[0].transform = 1;   // a transform at offset 0
    s.g[0].format = 4;      // R16G16B16_SFLOAT
    s.geometryCount = 2;
    s.g[1].indexType = 0;   // not indexed
    writeSpec(dir + "/build/triangles_two_geometries.bin", s, 512, 10);
    s = validSpec(0, 30);
    s.mode = 1 | 8;         // update, ppGeometries
    s.update = 2;           // new vertex data (not indexed: an update must keep the index values)
    s.g[0].indexType = 0;
    writeSpec(dir + "/build/triangles_update.bin", s, 512, 11);
    s = validSpec(1, 60);
    s.mode = 4 | 16;        // deferred, two infos
    s.buildFlags = 2;       // ALLOW_COMPACTION
    writeSpec(dir + "/build/aabbs_deferred_two_infos.bin", s, 512, 12);
    s = validSpec(2, 9);
    s.g[0].instances = 1;   // arrayOfPointers
    writeSpec(dir + "/build/instances_pointers.bin", s, 640, 13);
    s = validSpec(4, 20);
    s.g[0].lss = 1 | 2 | (1 << 3);  // SUCCESSIVE, CHAINED, index stride 1
    s.g[0].radius = 1;              // R16 radii
    s.mode = 1 | 2;                 // update in place
    writeSpec(dir + "/build/lss_successive_update.bin", s, 512, 14);
    s = validSpec(3, 20);
    s.g[0].indexType = 0;
    s.asOffset = 1;
    s.scratch = 5 << 2;
    writeSpec(dir + "/build/spheres_offsets.bin", s, 512, 15);

    // [NV-motion] Motion builds: motion triangles (alone, updated, next to static triangles), motion instances of
    // mixed and single types, in arrays and through typed pointers, and matrix motion with non-finite transforms
    // (which validation does not check: the build must bound or drop them).
    s = validSpec(0, 24);
    s.motion = 1;
    for (auto& g : s.g) g.motion = fz::kMotionTriangles | fz::kMotionNearVertices;
    writeSpec(dir + "/build/motion_triangles.bin", s, 512, 16);
    s.geometryCount = 2;
    s.g[0].indexType = 0;
    s.g[1].motion = 0;  // static triangles in a motion bottom level
    s.g[1].format = 4;  // R16G16B16_SFLOAT
    writeSpec(dir + "/build/motion_triangles_mixed.bin", s, 512, 17);
    s = validSpec(0, 30);
    s.motion = 1;
    s.mode = 1;         // update
    s.update = 2;       // new vertex data
    s.g[0].indexType = 0;
    s.g[0].motion = fz::kMotionTriangles | fz::kMotionNearVertices;
    writeSpec(dir + "/build/motion_triangles_update.bin", s, 512, 18);
    s = validSpec(2, 9);
    s.motion = 1;
    writeSpec(dir + "/build/motion_instances.bin", s, 512, 19);
    s.g[0].instances = 1;  // typed pointers
    writeSpec(dir + "/build/motion_instances_pointers.bin", s, 640, 20);
    s = validSpec(2, 6);
    s.motion = 1;
    s.g[0].motion = fz::kMotionOneType | (2 << 4);  // SRT
    writeSpec(dir + "/build/motion_instances_srt.bin", s, 512, 21);
    s.g[0].motion = fz::kMotionOneType | (1 << 4) | fz::kMotionNonFinite;  // matrix motion, NaN / inf
    writeSpec(dir + "/build/motion_instances_matrix_nonfinite.bin", s, 512, 22);
    s = validSpec(2, 7);
    s.motion = 1;
    s.mode = 1 | 2;     // update in place
    s.g[0].motion = fz::kMotionOneType | (1 << 4);
    writeSpec(dir + "/build/motion_instances_update.bin", s, 512, 23);
    return 0;
}
