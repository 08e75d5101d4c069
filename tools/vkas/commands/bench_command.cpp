#include "bench_command.hpp"

#include <chrono>
#include <cstdio>
#include <optional>
#include <random>
#include <stdexcept>
#include <thread>

#include "as_builder.hpp"
#include "input_error.hpp"
#include "json_writer.hpp"
#include "model_loader.hpp"
#include "progress.hpp"
#include "structure_file.hpp"

#include "rays.hpp"       // kit/measure: camera, diffuse and shadow rays
#include "vkas_side.hpp"  // kit/measure: vkas builds, refits and traversal
#if VKAS_TOOL_WITH_EMBREE
#include "embree_side.hpp"  // kit/measure: the same measurements with Embree 3
#endif

namespace vkas_tool {
namespace {

// The files' instanced triangles in world space, as one mesh (vb::Mesh: a padding float after the last vertex).
vb::Mesh flatten(const Scene& scene) {
    vb::Mesh m;
    for (const InstanceDesc& inst : scene.instances) {
        const GeometryDesc& g = scene.blases.at(inst.blas).geometries.at(0);
        const uint32_t base = static_cast<uint32_t>(m.vertexCount());
        for (const Vec3& p : g.mesh->positions) {
            const Vec3 w = inst.transform.point(p);
            m.vertices.insert(m.vertices.end(), {w.x, w.y, w.z});
        }
        for (uint32_t i : g.mesh->indices) m.indices.push_back(base + i);
    }
    m.vertices.push_back(0);
    return m;
}

std::vector<float> movedVertices(const vb::Mesh& m) {  // as vkas_bench_embree moves them: up to 1% outwards
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<float> v = m.vertices;
    for (size_t i = 0; i < 3 * m.vertexCount(); ++i) v[i] *= 1.0f + 0.01f * u(rng);
    return v;
}

// A value measured on both sides; embree < 0: not measured.
struct Row {
    std::string name, unit;
    double vkas = 0, embree = -1;
};

// Compaction through the Vulkan commands: the compacted-size query, then vkCopyAccelerationStructureKHR (COMPACT)
// into a structure of that size; the best time of `reps` copies.
double compactionMs(const Scene& scene, int reps, uint64_t& compacted, uint64_t& original) {
    DeviceOptions deviceOptions;
    deviceOptions.validation = false;
    VkContext ctx(deviceOptions);
    BlasDesc all;
    for (const InstanceDesc& inst : scene.instances) {
        GeometryDesc g = scene.blases.at(inst.blas).geometries.at(0);
        g.transform = inst.transform;
        all.geometries.push_back(g);
    }
    auto set = buildBottomLevel(ctx, {all}, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR);
    original = set->stats[0].size;
    compacted = queryStructureProperty(ctx, set->handles[0], VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR);
    HostBuffer dstBuffer(ctx, compacted, VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_STORAGE_BIT_KHR);
    VkAccelerationStructureCreateInfoKHR aci{VK_STRUCTURE_TYPE_ACCELERATION_STRUCTURE_CREATE_INFO_KHR};
    aci.buffer = dstBuffer.buffer();
    aci.size = compacted;
    aci.type = VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR;
    VkAccelerationStructureKHR dst = VK_NULL_HANDLE;
    check(ctx.vkCreateAccelerationStructureKHR(ctx.device(), &aci, nullptr, &dst), "vkCreateAccelerationStructureKHR");
    double best = 1e300;
    for (int r = 0; r < reps; ++r) {
        VkCopyAccelerationStructureInfoKHR copy{VK_STRUCTURE_TYPE_COPY_ACCELERATION_STRUCTURE_INFO_KHR};
        copy.src = set->handles[0];
        copy.dst = dst;
        copy.mode = VK_COPY_ACCELERATION_STRUCTURE_MODE_COMPACT_KHR;
        const auto t0 = std::chrono::steady_clock::now();
        const VkResult res = ctx.vkCopyAccelerationStructureKHR(ctx.device(), VK_NULL_HANDLE, &copy);
        best = std::min(best, vb::msSince(t0));
        if (res != VK_SUCCESS) {
            ctx.vkDestroyAccelerationStructureKHR(ctx.device(), dst, nullptr);
            check(res, "vkCopyAccelerationStructureKHR");
        }
    }
    ctx.vkDestroyAccelerationStructureKHR(ctx.device(), dst, nullptr);
    return best;
}

}  // namespace

int runBench(const BenchOptions& o) {
    if (o.files.empty()) throw std::invalid_argument("bench: give a mesh file");
    Scene scene;
    for (const std::string& f : o.files) {
        Progress::note("loading " + f);
        loadModel(f, scene);
    }
    vb::Scene sc;
    sc.name = o.files.size() == 1 ? o.files[0] : std::to_string(o.files.size()) + " files";
    sc.source = o.files[0];
    sc.mesh = flatten(scene);
    checkMemory(double(sc.mesh.triangleCount()) * 400.0 + double(o.rays) * 3 * 80, "benchmarking " + sc.name);
    const unsigned threads = o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency());
    const uint64_t tris = sc.mesh.triangleCount();
#if VKAS_TOOL_WITH_EMBREE
    const bool embree = o.embree;
#else
    const bool embree = false;
#endif
    std::vector<Row> rows;
    auto mprims = [&](double ms) { return ms > 0 ? double(tris) / ms / 1000.0 : 0.0; };

    vb::VkasEngine vk1(1), vkN(threads);
#if VKAS_TOOL_WITH_EMBREE
    std::optional<vb::EmbreeEngine> em1, emN;
    if (embree) em1.emplace(1), emN.emplace(threads);
    const RTCBuildQuality quality[3] = {RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH, RTC_BUILD_QUALITY_LOW};
#endif
    const char* prefName[3] = {"default", "fast-trace", "fast-build"};
    const VkBuildAccelerationStructureFlagsKHR prefFlags[3] = {
        0, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR};
    for (int p = 0; p < 3; ++p) {
        Progress::note(std::string("building (") + prefName[p] + ")");
        vb::VkasEngine::Build b = vk1.buildBottom(sc.mesh, prefFlags[p], o.reps);
        Row r1{std::string("build ") + prefName[p] + ", 1 thread", "Mtris/s", mprims(b.ms)};
        Row sah{std::string("SAH cost ") + prefName[p], "", vk1.sah(b.s).cost()};
        Row bytes{std::string("bytes/triangle ") + prefName[p], "B", double(b.compactedSize) / double(tris)};
        vk1.destroy(b.s);
        vb::VkasEngine::Build bn = vk1.buildBottom(sc.mesh, prefFlags[p], o.reps, threads);
        Row rn{std::string("build ") + prefName[p] + ", " + std::to_string(threads) + " threads", "Mtris/s", mprims(bn.ms)};
        vk1.destroy(bn.s);
#if VKAS_TOOL_WITH_EMBREE
        if (embree) {
            const vb::EmbreeEngine::Build e1 = em1->buildMesh(sc.mesh, quality[p], o.reps);
            const vb::EmbreeEngine::Build eN = emN->buildMesh(sc.mesh, quality[p], o.reps);
            r1.embree = mprims(e1.ms), rn.embree = mprims(eN.ms);
            bytes.embree = double(e1.bytes) / double(tris);
            sah.embree = em1->userBvhSah(sc.mesh, quality[p]).cost();
        }
#endif
        rows.insert(rows.end(), {r1, rn, bytes, sah});
    }
    {
        Progress::note("refitting");
        const std::vector<float> moved = movedVertices(sc.mesh);
        const VkBuildAccelerationStructureFlagsKHR f = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
        vb::VkasEngine::Build b = vk1.buildBottom(sc.mesh, f, 1);
        Row refit{"refit, 1 thread", "Mtris/s", mprims(vk1.refitBottom(b.s, sc.mesh, moved, f, o.reps))};
        vk1.destroy(b.s);
#if VKAS_TOOL_WITH_EMBREE
        if (embree) refit.embree = mprims(em1->refitMesh(sc.mesh, moved, o.reps).ms);
#endif
        rows.push_back(refit);
        uint64_t compacted = 0, original = 0;
        const double ms = compactionMs(scene, o.reps, compacted, original);
        rows.push_back({"compaction copy", "ms", ms});
        rows.push_back({"compacted / size query", "", double(compacted) / double(original)});
    }

    Progress::note("tracing");
    vb::VkasEngine::Build blas1 = vk1.buildBottom(sc.mesh, 0, 1), blasN = vkN.buildBottom(sc.mesh, 0, 1);
    vb::VkasEngine::Build tlas1 = vk1.buildTop({}, blas1.s.as, 0, 1), tlasN = vkN.buildTop({}, blasN.s.as, 0, 1);
    std::vector<VkasRay> rays[3];
    rays[0] = vb::cameraRays(sc, o.rays);
    std::vector<vb::Hit> cameraHits, hits;
    vkN.traceBatch(tlasN.s.as, false, rays[0], cameraHits, 1);
    bool anyHit = false;
    for (const vb::Hit& h : cameraHits) anyHit |= h.hit();
    if (!anyHit) throw InputError(o.files[0], "no camera ray hits the mesh (is it degenerate?)");
    rays[1] = vb::secondaryRays(sc, vb::RayKind::Diffuse, rays[0], cameraHits, o.rays);
    rays[2] = vb::secondaryRays(sc, vb::RayKind::Shadow, rays[0], cameraHits, o.rays);
#if VKAS_TOOL_WITH_EMBREE
    if (embree) emN->makeTraceScene(sc);
#endif
    const vb::RayKind kinds[3] = {vb::RayKind::Camera, vb::RayKind::Diffuse, vb::RayKind::Shadow};
    for (int k = 0; k < 3; ++k) {
        const bool shadow = k == 2;
        const double n = double(rays[k].size());
        Row r1{std::string(vb::rayKindName(kinds[k])) + " rays, 1 thread", "Mrays/s",
               n / vk1.traceBatch(tlas1.s.as, shadow, rays[k], hits, o.reps) / 1000.0};
        Row rn{std::string(vb::rayKindName(kinds[k])) + " rays, " + std::to_string(threads) + " threads", "Mrays/s",
               n / vkN.traceBatch(tlasN.s.as, shadow, rays[k], hits, o.reps) / 1000.0};
#if VKAS_TOOL_WITH_EMBREE
        if (embree) {
            r1.embree = n / emN->trace(vb::EmbreeCall::One, shadow, k == 0, rays[k], hits, 1, o.reps) / 1000.0;
            rn.embree = n / emN->trace(vb::EmbreeCall::One, shadow, k == 0, rays[k], hits, threads, o.reps) / 1000.0;
        }
#endif
        rows.insert(rows.end(), {r1, rn});
    }
    vk1.destroy(tlas1.s), vk1.destroy(blas1.s), vkN.destroy(tlasN.s), vkN.destroy(blasN.s);
    Progress::clear();

    if (o.json) {
        JsonWriter j;
        j.beginObject().value("scene", sc.name).value("triangles", tris).value("threads", uint64_t(threads));
        j.value("rays", uint64_t(o.rays)).value("reps", int64_t(o.reps)).value("embree", embree);
        j.beginArray("rows");
        for (const Row& r : rows) {
            j.beginObject().value("name", r.name).value("unit", r.unit).value("vkas", r.vkas);
            if (r.embree >= 0) j.value("embree", r.embree).value("ratio", r.embree > 0 ? r.vkas / r.embree : 0.0);
            j.end();
        }
        j.end().end();
        std::printf("%s\n", j.str().c_str());
        return 0;
    }
    std::printf("vkas bench: %s, %llu triangles, %u rays of each kind, best of %d, %u threads%s\n", sc.name.c_str(),
                static_cast<unsigned long long>(tris), o.rays, o.reps, threads,
                embree ? ", beside Embree 3" : " (Embree: not built in, or --no-embree)");
    std::printf("  %-34s %12s %12s %8s  %s\n", "", "vkas", embree ? "Embree" : "", embree ? "ratio" : "", "unit");
    for (const Row& r : rows) {
        if (r.embree >= 0)
            std::printf("  %-34s %12.3f %12.3f %7.2fx  %s\n", r.name.c_str(), r.vkas, r.embree,
                        r.embree > 0 ? r.vkas / r.embree : 0.0, r.unit.c_str());
        else
            std::printf("  %-34s %12.3f %12s %8s  %s\n", r.name.c_str(), r.vkas, "", "", r.unit.c_str());
    }
    return 0;
}

}  // namespace vkas_tool
