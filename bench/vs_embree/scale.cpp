#include "scale.hpp"

#include "embree_side.hpp"
#include "judge.hpp"
#include "rays.hpp"
#include "scenes.hpp"
#include "vkas_side.hpp"

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>

namespace vb {

namespace {

// Copies of `m` on a square grid, one mesh: at least minTriangles triangles.
Mesh tiled(const Mesh& m, size_t minTriangles) {
    const size_t copies = (minTriangles + m.triangleCount() - 1) / m.triangleCount();
    const size_t side = size_t(std::ceil(std::sqrt(double(copies))));
    const Box b = meshBounds(m);
    const float step = 1.1f * std::max(b.hi[0] - b.lo[0], b.hi[2] - b.lo[2]);
    Mesh out;
    out.vertices.reserve(copies * m.vertices.size());
    out.indices.reserve(copies * m.indices.size());
    for (size_t c = 0; c < copies; ++c) {
        const uint32_t base = uint32_t(out.vertexCount());
        const float dx = step * float(c % side), dz = step * float(c / side);
        for (size_t i = 0; i < m.vertexCount(); ++i) {
            out.vertices.push_back(m.vertices[3 * i] + dx);
            out.vertices.push_back(m.vertices[3 * i + 1]);
            out.vertices.push_back(m.vertices[3 * i + 2] + dz);
        }
        for (uint32_t idx : m.indices) out.indices.push_back(base + idx);
    }
    return out;
}

double peakRssGb() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) * 1024 / 1e9;
}

}  // namespace

void runScaleRun(size_t minTriangles, unsigned threads, size_t rayCount, const std::string& dataDir, Json& json) {
    const auto t0 = std::chrono::steady_clock::now();
    Scene sc = makeScene("bunny-4m", false, dataDir, 0);
    sc.name = "scale";
    sc.mesh = tiled(sc.mesh, minTriangles);
    sc.source = "copies of bunny-4m";
    const double tris = double(sc.mesh.triangleCount());
    std::printf("\nscale run: %.0f triangles (%zu copies of bunny-4m), %u threads, %zu rays per kind; mesh made in %.1f s\n",
                tris, size_t(tris) / 4458624, threads, rayCount,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    const double inputBytes = double(sc.mesh.vertices.size() * 4 + sc.mesh.indices.size() * 4);

    VkasEngine vk(threads);
    VkasEngine::Build b = vk.buildBottom(sc.mesh, 0, 1, threads);
    const double vkPeak = double(b.sizeQuery + b.scratchSize);
    VkasEngine::Build top = vk.buildTop({}, b.s.as, 0, 1);
    std::printf("  vkas   deferred build, %2u joined threads: %9.1f ms %7.2f Mtris/s | peak (structure buffer + scratch) "
                "%6.2f GB, %6.1f B/tri | built %6.2f GB (%5.1f B/tri), compacted %6.2f GB | sizes query / built %.2f\n",
                threads, b.ms, tris / b.ms / 1000, vkPeak / 1e9, vkPeak / tris, double(b.usedSize) / 1e9,
                double(b.usedSize) / tris, double(b.compactedSize) / 1e9, double(b.sizeQuery) / double(b.usedSize));

    EmbreeEngine em(threads);
    const EmbreeEngine::Build e = em.buildMesh(sc.mesh, RTC_BUILD_QUALITY_MEDIUM, 1);
    std::printf("  Embree MEDIUM build, %2u threads:          %9.1f ms %7.2f Mtris/s | peak (monitor)                   "
                "%6.2f GB, %6.1f B/tri | built %6.2f GB (%5.1f B/tri)\n",
                threads, e.ms, tris / e.ms / 1000, double(e.peakBytes) / 1e9, double(e.peakBytes) / tris,
                double(e.bytes) / 1e9, double(e.bytes) / tris);
    std::printf("  input (vertices + 32-bit indices, shared by both): %.2f GB; vkas / Embree: build speed %.2fx, peak "
                "memory %.2fx\n", inputBytes / 1e9, e.ms / b.ms, vkPeak / double(e.peakBytes));

    json.begin("scale", '{').field("triangles", tris).field("threads", double(threads)).field("input_bytes", inputBytes);
    json.field("vkas_build_ms", b.ms).field("vkas_peak_bytes", vkPeak).field("vkas_size_query_bytes", double(b.sizeQuery));
    json.field("vkas_scratch_bytes", double(b.scratchSize)).field("vkas_built_bytes", double(b.usedSize));
    json.field("vkas_compacted_bytes", double(b.compactedSize)).field("embree_build_ms", e.ms);
    json.field("embree_peak_bytes", double(e.peakBytes)).field("embree_bytes", double(e.bytes));

    // Tracing: camera rays, then diffuse rays from Embree's camera hits, on all threads; hits compared.
    em.makeTraceScene(sc);
    std::vector<VkasRay> rays[2];
    rays[0] = cameraRays(sc, rayCount);
    std::vector<Hit> cameraHits;
    em.trace(EmbreeCall::One, false, true, rays[0], cameraHits, threads, 1);
    rays[1] = secondaryRays(sc, RayKind::Diffuse, rays[0], cameraHits, rayCount);
    std::unique_ptr<Judge> judge;
    json.begin("traversal", '[');
    for (int k = 0; k < 2; ++k) {
        std::vector<Hit> vh, eh;
        const double vms = vk.traceBatch(top.s.as, false, rays[k], vh, 1);
        const double ems = em.trace(EmbreeCall::One, false, k == 0, rays[k], eh, threads, 1);
        size_t same = 0, hitMiss = 0, otherPrim = 0, judged = 0, vkasWrong = 0;
        for (size_t i = 0; i < rays[k].size(); ++i) {
            const Hit &a = vh[i], &c = eh[i];
            if (a.hit() == c.hit() && (!a.hit() || a.prim == c.prim)) {
                ++same;
                continue;
            }
            (a.hit() != c.hit() ? hitMiss : otherPrim)++;
            if (judged < 8) {  // each judgement tests every triangle in double precision
                if (!judge) judge = std::make_unique<Judge>(sc);
                const Judgement j = judge->judge(rays[k][i], a, c, false);
                vkasWrong += !j.vkasOk;
                ++judged;
            }
        }
        const char* kind = k == 0 ? "camera" : "diffuse";
        std::printf("  %-7s rays, %2u threads: vkasTraceRays %8.2f Mrays/s, Embree rtcIntersect1 %8.2f Mrays/s (%.2fx); "
                    "hits: %zu same, %zu hit/miss, %zu other primitive; oracle on %zu of those: vkas wrong on %zu\n",
                    kind, threads, double(rays[k].size()) / vms / 1000, double(rays[k].size()) / ems / 1000, ems / vms,
                    same, hitMiss, otherPrim, judged, vkasWrong);
        json.begin(nullptr, '{').field("rays", kind).field("vkas_ms", vms).field("embree_ms", ems);
        json.field("same", double(same)).field("hit_miss", double(hitMiss)).field("other_primitive", double(otherPrim));
        json.field("judged", double(judged)).field("vkas_wrong", double(vkasWrong)).end('}');
    }
    json.end(']');

    // Past 4 GiB through serialization: the blob of the bottom level, deserialized, must trace as the original.
    {
        VkasEngine::RoundTrip rt = vk.serializeRoundTrip(b.s, b.sizeQuery, b.usedSize);
        VkasEngine::Build top2 = vk.buildTop({}, rt.s.as, 0, 1);
        std::vector<Hit> before, after;
        vk.traceBatch(top.s.as, false, rays[1], before, 1);
        vk.traceBatch(top2.s.as, false, rays[1], after, 1);
        size_t differ = 0;
        for (size_t i = 0; i < before.size(); ++i)
            differ += before[i].hit() != after[i].hit() || before[i].prim != after[i].prim || before[i].t != after[i].t;
        std::printf("  serialized blob %.2f GB (%s 4 GiB) in %.1f ms, deserialized in %.1f ms; deserialized bytes %s the "
                    "built structure's; diffuse hits differing after the round trip: %zu of %zu\n",
                    double(rt.blobBytes) / 1e9, rt.blobBytes > (uint64_t(1) << 32) ? "past" : "below", rt.serializeMs,
                    rt.deserializeMs, rt.bytesEqual ? "equal" : "DIFFER FROM", differ, before.size());
        json.field("blob_bytes", double(rt.blobBytes)).field("serialize_ms", rt.serializeMs);
        json.field("deserialize_ms", rt.deserializeMs).field("round_trip_bytes_equal", rt.bytesEqual ? 1.0 : 0.0);
        json.field("round_trip_hits_differing", double(differ));
        vk.destroy(top2.s);
        vk.destroy(rt.s);
    }
    json.field("peak_rss_bytes", peakRssGb() * 1e9).end('}');
    std::printf("  process peak resident memory: %.2f GB\n", peakRssGb());
    vk.destroy(top.s);
    vk.destroy(b.s);
}

}  // namespace vb
