// vkas_bench_embree: vkas against Intel Embree 3 in one process, on the same meshes and rays (issues 7 and 15).
// Builds (default, PREFER_FAST_TRACE, PREFER_FAST_BUILD, refit against Embree MEDIUM, HIGH, LOW, REFIT; one thread),
// traversal (camera, diffuse, shadow rays; vkasTraceRays and vkasRayQuery* against rtcIntersect1/rtcOccluded1 on one
// thread and against Embree's best call on all threads, each on a ROBUST scene and on one with Embree's default
// flags), hit agreement, deferred-build thread scaling, issue 15's targets, and a dump / comparison of the hits of
// two vkas builds (--dump-hits, --compare-hits). Prints one table and optionally writes JSON. See
// docs/PERFORMANCE.md ("Comparison with Embree").
#include "embree_side.hpp"
#include "hitfile.hpp"
#include "judge.hpp"
#include "rays.hpp"
#include "report.hpp"
#include "scale.hpp"
#include "scenes.hpp"
#include "vkas_side.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>

using namespace vb;

namespace {

struct Options {
    std::vector<std::string> scenes, meshes;
    unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    size_t rays = 0;
    int reps = 0;
    unsigned instances = 0;
    std::string json, threadsList, dataDir;
    std::vector<std::string> scalingScenes;
    size_t scaleTriangles = 0;  // --scale: the triangles of the scale run's mesh (0: no scale run)
    bool quick = false, noScaling = false;
    std::string showDisagreements;  // empty: none; "all" or a number: that many rays per kind
    std::string dumpHits, compareHits;
};

struct Target {
    std::string scene, what;
    double value, goal;
    bool higherIsBetter;
};

struct Variant {
    const char* name;
    VkBuildAccelerationStructureFlagsKHR flags;
    const char* embreeName;
    RTCBuildQuality quality;
};
const Variant kVariants[] = {
    {"default", 0, "MEDIUM", RTC_BUILD_QUALITY_MEDIUM},
    {"PREFER_FAST_TRACE", VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR, "HIGH", RTC_BUILD_QUALITY_HIGH},
    {"PREFER_FAST_BUILD", VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR, "LOW", RTC_BUILD_QUALITY_LOW},
};

struct BuildRow {
    std::string vkasName, embreeName;
    double vkasMs, vkasBytes, vkasSah, embreeMs, embreeBytes, embreeSah;  // bytes per primitive; SAH < 0: not known
    // vkas, bytes: the build-sizes query's accelerationStructureSize, the compacted size, ACCELERATION_STRUCTURE_SIZE
    double sizeQuery = 0, compacted = 0, used = 0;
};

std::string ratio(double r) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2fx", r);
    return b;
}

std::vector<float> movedVertices(const Mesh& m) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<float> v = m.vertices;
    for (size_t i = 0; i < 3 * m.vertexCount(); ++i) v[i] *= 1.0f + 0.01f * u(rng);
    return v;
}

std::vector<Transform> movedInstances(const Scene& s) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    const double d = meshBounds(s.mesh).diagonal() * 0.05;
    std::vector<Transform> xs = s.instances;
    for (Transform& x : xs) x[3] += float(d * u(rng)), x[7] += float(d * u(rng)), x[11] += float(d * u(rng));
    return xs;
}

class Bench {
public:
    explicit Bench(const Options& o) : o_(o) {}
    std::vector<Target> targets;
    Json json;
    std::unique_ptr<HitFileWriter> dump;
    std::unique_ptr<HitFileReader> compare;
    size_t hitsDifferent = 0, hitsRefused = 0;  // --compare-hits: rays that differ (not ties); sections not compared

    void runScene(const Scene& sc);
    // flags 0 against MEDIUM (with issue 17's targets) or PREFER_FAST_BUILD against LOW.
    void runScaling(const Scene& sc, const std::vector<unsigned>& threadCounts, VkBuildAccelerationStructureFlagsKHR flags);

private:
    void printBuilds(const Scene& sc, const std::vector<BuildRow>& rows);
    const Options& o_;
};

void Bench::printBuilds(const Scene& sc, const std::vector<BuildRow>& rows) {
    const bool inst = sc.manyInstances();
    const double n = double(inst ? sc.instances.size() : sc.mesh.triangleCount());
    const char* unit = inst ? "inst" : "tri";
    std::printf("  %-22s %9s %8s %7s %6s | %-22s %9s %8s %7s %6s | %6s %6s %6s\n", "build, 1 thread", "vkas ms",
                inst ? "Minst/s" : "Mtris/s", inst ? "B/inst" : "B/tri", "SAH", "Embree", "ms", inst ? "Minst/s" : "Mtris/s",
                inst ? "B/inst" : "B/tri", "SAH", "speed", "bytes", "SAH");
    json.begin("builds", '[');
    for (const BuildRow& r : rows) {
        auto sah = [](double s) {
            char b[16];
            if (s < 0) return std::string("-");
            std::snprintf(b, sizeof b, "%.1f", s);
            return std::string(b);
        };
        char eb[16] = "-";  // Embree's monitor saw no net allocation (e.g. memory reused by its allocator)
        if (r.embreeBytes > 0) std::snprintf(eb, sizeof eb, "%.1f", r.embreeBytes);
        std::printf("  %-22s %9.1f %8.2f %7.1f %6s | %-22s %9.1f %8.2f %7s %6s | %6s %6s %6s\n", r.vkasName.c_str(),
                    r.vkasMs, n / r.vkasMs / 1000, r.vkasBytes, sah(r.vkasSah).c_str(), r.embreeName.c_str(), r.embreeMs,
                    n / r.embreeMs / 1000, eb, sah(r.embreeSah).c_str(), ratio(r.embreeMs / r.vkasMs).c_str(),
                    r.embreeBytes > 0 ? ratio(r.vkasBytes / r.embreeBytes).c_str() : "-",
                    r.vkasSah >= 0 && r.embreeSah >= 0 ? ratio(r.vkasSah / r.embreeSah).c_str() : "-");
        json.begin(nullptr, '{').field("vkas", r.vkasName).field("vkas_ms", r.vkasMs).field("vkas_mprims_per_s", n / r.vkasMs / 1000);
        json.field((std::string("vkas_bytes_per_") + unit).c_str(), r.vkasBytes).field("vkas_sah", r.vkasSah);
        json.field("embree", r.embreeName).field("embree_ms", r.embreeMs).field("embree_mprims_per_s", n / r.embreeMs / 1000);
        json.field((std::string("embree_bytes_per_") + unit).c_str(), r.embreeBytes).field("embree_sah", r.embreeSah);
        json.field("speed_ratio", r.embreeMs / r.vkasMs).field("vkas_size_query_bytes", r.sizeQuery);
        json.field("vkas_compacted_bytes", r.compacted).field("vkas_structure_size_bytes", r.used);
        json.field("size_query_over_compacted", r.sizeQuery / r.compacted).end('}');
    }
    json.end(']');
    std::printf("  build-sizes query (accelerationStructureSize) / compacted size:");
    for (const BuildRow& r : rows)
        std::printf(" %s %s (%.0f / %.0f B)%s", r.vkasName.c_str(), ratio(r.sizeQuery / r.compacted).c_str(), r.sizeQuery,
                    r.compacted, &r == &rows.back() ? "\n" : ",");
    for (const BuildRow& r : rows)
        if (r.sizeQuery < r.used || r.sizeQuery < r.compacted)
            std::printf("  WARNING: %s: the build-sizes query (%.0f B) is below the structure's size (%.0f B, compacted "
                        "%.0f B)\n", r.vkasName.c_str(), r.sizeQuery, r.used, r.compacted);
}

void Bench::runScene(const Scene& sc) {
    const bool inst = sc.manyInstances();
    const size_t tris = sc.mesh.triangleCount();
    const double prims = double(inst ? sc.instances.size() : tris);
    std::printf("\nscene %s: %zu triangles", sc.name.c_str(), tris);
    if (inst) std::printf(" x %zu instances", sc.instances.size());
    std::printf("%s  (%s)\n", sc.thin ? ", long thin triangles" : "", sc.source.c_str());
    json.begin(nullptr, '{').field("name", sc.name).field("source", sc.source).field("triangles", double(tris));
    json.field("instances", double(sc.instances.size())).field("long_thin", sc.thin);

    VkasEngine vk1(1), vkN(o_.threads);
    EmbreeEngine em1(1), emN(o_.threads);

    // The rays, from Embree's closest hits of the camera rays (untimed).
    emN.makeTraceScene(sc);
    std::vector<VkasRay> rays[3];
    rays[0] = cameraRays(sc, o_.rays);
    std::vector<Hit> cameraHits;
    emN.trace(EmbreeCall::One, false, true, rays[0], cameraHits, o_.threads, 1);
    rays[1] = secondaryRays(sc, RayKind::Diffuse, rays[0], cameraHits, o_.rays);
    rays[2] = secondaryRays(sc, RayKind::Shadow, rays[0], cameraHits, o_.rays);

    // --- builds ---
    std::vector<BuildRow> rows;
    double variantRate[3][3] = {};  // [variant][ray kind] Mrays/s, vkasTraceRays on 1 thread
    std::vector<Hit> vkBatch1[3];   // default build, 1 thread
    VkasEngine::Structure blas{}, defaultTlas{};
    std::vector<Box> instanceBoxes;
    if (inst) {
        VkasEngine::Build b = vk1.buildBottom(sc.mesh, 0, 1);
        blas = b.s;
        for (const Transform& x : sc.instances) instanceBoxes.push_back(transformBox(meshBounds(sc.mesh), x));
    }
    for (int v = 0; v < 3; ++v) {
        const Variant& var = kVariants[v];
        BuildRow row{var.name, var.embreeName};
        VkasEngine::Build b = inst ? vk1.buildTop(sc.instances, blas.as, var.flags, o_.reps)
                                   : vk1.buildBottom(sc.mesh, var.flags, o_.reps);
        row.vkasMs = b.ms, row.vkasBytes = double(b.compactedSize) / prims, row.vkasSah = vk1.sah(b.s).cost();
        row.sizeQuery = double(b.sizeQuery), row.compacted = double(b.compactedSize), row.used = double(b.usedSize);
        VkasEngine::Build top = inst ? b : vk1.buildTop({}, b.s.as, 0, 1);
        for (int k = 0; k < 3; ++k) {
            std::vector<Hit> hits;
            variantRate[v][k] = double(o_.rays) / vk1.traceBatch(top.s.as, k == 2, rays[k], hits, o_.reps) / 1000;
            if (v == 0) vkBatch1[k] = std::move(hits);
        }
        const EmbreeEngine::Build e = inst ? em1.buildInstances(sc.mesh, sc.instances, var.quality, o_.reps)
                                           : em1.buildMesh(sc.mesh, var.quality, o_.reps);
        row.embreeMs = e.ms, row.embreeBytes = double(e.bytes) / prims;
        row.embreeSah = inst ? em1.userBvhSah(instanceBoxes, var.quality).cost() : em1.userBvhSah(sc.mesh, var.quality).cost();
        rows.push_back(row);
        if (v == 0) {
            defaultTlas = top.s;
        } else {
            if (!inst) vk1.destroy(top.s);
            vk1.destroy(b.s);
        }
    }
    {  // refit
        BuildRow row{"refit (MODE_UPDATE)", inst ? "REFIT (dynamic recommit)" : "REFIT"};
        const auto flags = VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
        VkasEngine::Build b = inst ? vk1.buildTop(sc.instances, blas.as, flags, 1) : vk1.buildBottom(sc.mesh, flags, 1);
        const auto movedXs = inst ? movedInstances(sc) : std::vector<Transform>{};
        const auto movedV = inst ? std::vector<float>{} : movedVertices(sc.mesh);
        row.vkasMs = inst ? vk1.refitTop(b.s, sc.instances, movedXs, blas.as, flags, o_.reps)
                          : vk1.refitBottom(b.s, sc.mesh, movedV, flags, o_.reps);
        row.vkasBytes = double(b.compactedSize) / prims, row.vkasSah = vk1.sah(b.s).cost();
        row.sizeQuery = double(b.sizeQuery), row.compacted = double(b.compactedSize), row.used = double(b.usedSize);
        const EmbreeEngine::Build e = inst ? em1.recommitInstances(sc.mesh, sc.instances, movedXs, o_.reps)
                                           : em1.refitMesh(sc.mesh, movedV, o_.reps);
        row.embreeMs = e.ms, row.embreeBytes = double(e.bytes) / prims, row.embreeSah = -1;
        rows.push_back(row);
        vk1.destroy(b.s);
    }
    printBuilds(sc, rows);

    // --- traversal ---
    VkasEngine::Structure nBlas{}, nTlas{};
    if (inst) {
        nBlas = vkN.buildBottom(sc.mesh, 0, 1).s;
        nTlas = vkN.buildTop(sc.instances, nBlas.as, 0, 1).s;
    } else {
        nBlas = vkN.buildBottom(sc.mesh, 0, 1).s;
        nTlas = vkN.buildTop({}, nBlas.as, 0, 1).s;
    }
    std::printf("  %-8s %-9s %-30s %8s | %-22s %8s %6s | %-22s %8s %6s | %7s\n", "rays", "threads", "vkas", "Mrays/s",
                "Embree ROBUST", "Mrays/s", "ratio", "Embree default flags", "Mrays/s", "ratio", "/batch");
    json.begin("traversal", '[');
    double rate[3][4] = {};  // [kind]: vkas batch 1, vkas query 1, Embree 1 thread (ROBUST), vkas batch N
    double emDefault1[3] = {};                   // Embree 1 thread, the default flags
    double emBestN[3] = {}, emDefaultBestN[3] = {};  // Embree's best call on all threads: ROBUST, default flags
    std::string agreementText[3];
    const size_t n = o_.rays;
    const Judge judge(sc);  // the oracle, for the rays where vkas and Embree differ
    size_t showLimit = 0;
    if (!o_.showDisagreements.empty())
        showLimit = o_.showDisagreements == "all" ? SIZE_MAX : size_t(std::stoull(o_.showDisagreements));
    auto row = [](const char* kind, const std::string& threads, const std::string& vkName, double vk, const std::string& e,
                  double er, const std::string& ed, double edr, const std::string& extra) {
        std::printf("  %-8s %-9s %-30s %8.3f | %-22s %8.3f %6s | %-22s %8.3f %6s | %7s\n", kind, threads.c_str(),
                    vkName.c_str(), vk, e.c_str(), er, ratio(vk / er).c_str(), ed.c_str(), edr, ratio(vk / edr).c_str(),
                    extra.c_str());
    };
    for (int k = 0; k < 3; ++k) {
        const bool anyHit = k == 2, coherent = k == 0;
        const char* kind = rayKindName(RayKind(k));
        std::vector<Hit> em1Hits, rqHits, batchN, tmp, emClosest;
        const double emMs = emN.trace(EmbreeCall::One, anyHit, coherent, rays[k], em1Hits, 1, o_.reps);
        const double emDMs = emN.trace(EmbreeCall::One, anyHit, coherent, rays[k], tmp, 1, o_.reps, TraceScene::Default);
        const double rqMs = vk1.traceRayQuery(defaultTlas.as, anyHit, rays[k], rqHits, o_.reps);
        const double bNMs = vkN.traceBatch(nTlas.as, anyHit, rays[k], batchN, o_.reps);
        rate[k][0] = variantRate[0][k], rate[k][1] = n / rqMs / 1000, rate[k][2] = n / emMs / 1000, rate[k][3] = n / bNMs / 1000;
        emDefault1[k] = n / emDMs / 1000;
        const char* mode = anyHit ? "any-hit" : "closest";
        const std::string batchName = std::string("vkasTraceRays ") + mode;
        const char* e1 = embreeCallName(EmbreeCall::One, anyHit);
        row(kind, "1", batchName, rate[k][0], e1, rate[k][2], e1, emDefault1[k], "");
        row(kind, "1", "vkasRayQuery*", rate[k][1], e1, rate[k][2], e1, emDefault1[k], ratio(rate[k][1] / rate[k][0]));
        json.begin(nullptr, '{').field("rays", kind).field("threads", 1.0).field("vkas_batch_mrays", rate[k][0]);
        json.field("vkas_ray_query_mrays", rate[k][1]).field("embree_call", e1).field("embree_mrays", rate[k][2]);
        json.field("embree_default_flags_mrays", emDefault1[k]).field("batch_vs_embree", rate[k][0] / rate[k][2]);
        json.field("batch_vs_embree_default_flags", rate[k][0] / emDefault1[k]);
        json.field("ray_query_vs_batch", rate[k][1] / rate[k][0]).end('}');
        // All threads: Embree's calls on both scenes, the best one named.
        EmbreeCall best = EmbreeCall::One, bestDefault = EmbreeCall::One;
        json.begin(nullptr, '{').field("rays", kind).field("threads", double(o_.threads)).field("vkas_batch_mrays", rate[k][3]);
        for (EmbreeCall c : {EmbreeCall::One, EmbreeCall::Packet8, EmbreeCall::Packet16, EmbreeCall::Stream}) {
            const double r = n / emN.trace(c, anyHit, coherent, rays[k], tmp, o_.threads, o_.reps) / 1000;
            json.field((std::string("embree_") + embreeCallName(c, anyHit) + "_mrays").c_str(), r);
            if (r > emBestN[k]) emBestN[k] = r, best = c;
            const double rd = n / emN.trace(c, anyHit, coherent, rays[k], tmp, o_.threads, o_.reps, TraceScene::Default) / 1000;
            json.field((std::string("embree_default_flags_") + embreeCallName(c, anyHit) + "_mrays").c_str(), rd);
            if (rd > emDefaultBestN[k]) emDefaultBestN[k] = rd, bestDefault = c;
        }
        json.field("embree_best_call", embreeCallName(best, anyHit)).field("embree_best_mrays", emBestN[k]);
        json.field("embree_default_flags_best_call", embreeCallName(bestDefault, anyHit));
        json.field("embree_default_flags_best_mrays", emDefaultBestN[k]).field("batch_vs_embree_best", rate[k][3] / emBestN[k]);
        json.field("batch_vs_embree_default_flags_best", rate[k][3] / emDefaultBestN[k]).end('}');
        row(kind, std::to_string(o_.threads), batchName, rate[k][3], std::string(embreeCallName(best, anyHit)) + " (best)",
            emBestN[k], std::string(embreeCallName(bestDefault, anyHit)) + " (best)", emDefaultBestN[k], "");
        // Agreement with Embree, and vkas's paths with each other.
        if (anyHit) emN.trace(EmbreeCall::One, false, false, rays[k], emClosest, o_.threads, 1);
        // Every ray where the results differ, decided by the oracle (judge.hpp).
        const std::vector<size_t> differing = differingRays(rays[k], vkBatch1[k], em1Hits, anyHit);
        std::vector<Judgement> verdicts(differing.size());
        parallelFor(o_.threads, differing.size(), 1, [&](size_t b, size_t e) {
            for (size_t d = b; d < e; ++d) {
                const size_t i = differing[d];
                verdicts[d] = judge.judge(rays[k][i], vkBatch1[k][i], em1Hits[i], anyHit);
            }
        });
        const Agreement g = compareHits(rays[k], vkBatch1[k], em1Hits, anyHit, anyHit ? &emClosest : nullptr, differing, verdicts);
        const size_t rqDiff = countDifferent(vkBatch1[k], rqHits), nDiff = countDifferent(vkBatch1[k], batchN);
        for (size_t d = 0; d < differing.size() && d < showLimit; ++d) {
            const size_t i = differing[d];
            const Category c = classify(rays[k][i], vkBatch1[k][i], em1Hits[i], anyHit, anyHit ? emClosest[i] : Hit{});
            std::printf("    %s\n", disagreementText(kind, i, rays[k][i], c, verdicts[d], anyHit).c_str());
        }
        agreementText[k] = std::string(kind) + " vs " + e1 + ": " + describe(g, anyHit) +
                           "; vkas ray query vs batch: " + std::to_string(rqDiff) + " differ, batch " +
                           std::to_string(o_.threads) + " threads vs 1: " + std::to_string(nDiff) + " differ";
        json.begin(nullptr, '{').field("rays", kind).field("agreement_rays", double(g.rays));
        json.field("hit_miss", double(g.hitMiss)).field("hit_miss_at_edge", double(g.hitMissAtEdge));
        json.field("hit_miss_at_tmax", double(g.hitMissAtEnd)).field("ties", double(g.tie));
        json.field("different_hits_past_edge", double(g.differentHitAtEdge)).field("different_hits", double(g.differentHit));
        json.field("same_primitive_t_beyond_tolerance", double(g.sameBeyondT)).field("differing", double(g.differing));
        json.field("oracle_both_acceptable", double(g.bothAcceptable)).field("oracle_vkas_right", double(g.vkasRight));
        json.field("oracle_embree_right", double(g.embreeRight)).field("unexplained", double(g.disagreements()));
        json.field("exact_vkas_only", double(g.exactVkasOnly)).field("exact_embree_only", double(g.exactEmbreeOnly));
        json.field("exact_neither", double(g.exactNeither)).field("max_vkas_error_float_units", g.maxVkasError);
        json.field("max_embree_error_float_units", g.maxEmbreeError);
        json.field("max_rel_t_diff", g.maxRelT).field("max_t_diff_over_tolerance", g.maxTolT).field("ray_query_vs_batch_differ", double(rqDiff));
        json.field("batch_threads_vs_1_differ", double(nDiff)).end('}');
    }
    for (int v = 1; v < 3; ++v)
        for (int k = 0; k < 3; ++k) {
            const std::string name = std::string("vkasTraceRays ") + kVariants[v].name;
            std::printf("  %-8s %-9s %-30s %8.3f | %-22s %8.3f %6s |\n", rayKindName(RayKind(k)), "1", name.c_str(),
                        variantRate[v][k], "(vkas default build)", variantRate[0][k],
                        ratio(variantRate[v][k] / variantRate[0][k]).c_str());
            json.begin(nullptr, '{').field("rays", rayKindName(RayKind(k))).field("threads", 1.0);
            json.field("vkas_variant", kVariants[v].name).field("vkas_batch_mrays", variantRate[v][k]);
            json.field("vkas_default_batch_mrays", variantRate[0][k]).end('}');
        }
    json.end(']');
    std::printf("  agreement (vkasTraceRays 1 thread, default build, against Embree ROBUST):\n");
    for (const std::string& s : agreementText) std::printf("    %s\n", s.c_str());

    // --- the hits of another vkas build (--dump-hits, --compare-hits) ---
    if (dump)
        for (int k = 0; k < 3; ++k) dump->add(sc.name, RayKind(k), rays[k], vkBatch1[k]);
    if (compare) {
        std::printf("  hits (vkasTraceRays 1 thread, default build) against %s:\n", compare->path().c_str());
        json.begin("hit_comparison", '[');
        for (int k = 0; k < 3; ++k) {
            const bool anyHit = k == 2;
            const char* kind = rayKindName(RayKind(k));
            json.begin(nullptr, '{').field("rays", kind);
            HitFileReader::Section* sec = compare->take(sc.name, RayKind(k));
            const uint64_t hash = rayHash(rays[k]);
            if (!sec) {
                std::printf("    %-8s not compared (not in the file)\n", kind);
                json.field("compared", false).field("why", "not in the file");
            } else if (sec->rays != rays[k].size() || sec->hash != hash) {
                std::printf("    %-8s NOT COMPARED: the rays differ from the file's (%llu rays, hash %016llx; this run: %zu, "
                            "%016llx): not the same options?\n",
                            kind, (unsigned long long)sec->rays, (unsigned long long)sec->hash, rays[k].size(),
                            (unsigned long long)hash);
                json.field("compared", false).field("why", "the rays differ from the file's");
                ++hitsRefused;
            } else {
                const std::vector<Hit> before = compare->read(*sec);
                const HitComparison c = compareHitSets(rays[k], vkBatch1[k], before, anyHit, judge, o_.threads);
                std::printf("    %-8s %zu rays: %zu identical, %zu ties (another primitive at the same t, or both acceptable "
                            "to the oracle), %zu different%s\n",
                            kind, c.rays, c.identical, c.ties, c.different.size(), c.different.empty() ? "" : ":");
                for (size_t d = 0; d < c.different.size(); ++d) {
                    const size_t i = c.different[d];
                    std::printf("      %s\n",
                                hitDifferenceText(kind, i, rays[k][i], vkBatch1[k][i], before[i], c.verdicts[d], anyHit).c_str());
                }
                hitsDifferent += c.different.size();
                json.field("compared", true).field("rays_compared", double(c.rays)).field("identical", double(c.identical));
                json.field("ties", double(c.ties)).field("different", double(c.different.size()));
            }
            json.end('}');
        }
        json.end(']');
    }
    json.end('}');

    // --- targets (issue 15) ---
    const std::string s = sc.name;
    const BuildRow& def = rows[0];
    targets.push_back({s, "vkasTraceRays closest, camera, 1 thread >= 1.25x rtcIntersect1", rate[0][0] / rate[0][2], 1.25, true});
    targets.push_back({s, "vkasTraceRays closest, diffuse, 1 thread >= 1.25x rtcIntersect1", rate[1][0] / rate[1][2], 1.25, true});
    targets.push_back({s, "vkasTraceRays any-hit, shadow, 1 thread >= 1.25x rtcOccluded1", rate[2][0] / rate[2][2], 1.25, true});
    for (int k = 0; k < 3; ++k)
        targets.push_back({s, std::string("vkasRayQuery* ") + rayKindName(RayKind(k)) + " >= 0.9x vkasTraceRays, 1 thread",
                           rate[k][1] / rate[k][0], 0.9, true});
    for (int k = 0; k < 3; ++k)
        targets.push_back({s, std::string("vkasTraceRays ") + rayKindName(RayKind(k)) + ", all threads >= Embree's best call",
                           rate[k][3] / emBestN[k], 1.0, true});
    if (inst) {
        targets.push_back({s, "compacted bytes per instance <= Embree MEDIUM's", def.vkasBytes / def.embreeBytes, 1.0, false});
    } else {
        targets.push_back({s, "compacted bytes per triangle <= 0.75x Embree MEDIUM's", def.vkasBytes / def.embreeBytes, 0.75, false});
        targets.push_back({s, "build-sizes query <= 1.3x the compacted size", def.sizeQuery / def.compacted, 1.3, false});
        targets.push_back({s, "build-sizes query >= the structure's size (a safe bound)",
                           def.sizeQuery / std::max(def.used, def.compacted), 1.0, true});
    }

    // --- targets (issue 17): the builders ---
    const BuildRow &fastTrace = rows[1], &fastBuild = rows[2], &refit = rows[3];
    targets.push_back({s, "[17] default build, 1 thread >= 1.5x Embree MEDIUM", def.embreeMs / def.vkasMs, 1.5, true});
    if (def.vkasSah >= 0 && def.embreeSah > 0)
        targets.push_back({s, "[17] default build's SAH cost <= Embree MEDIUM's", def.vkasSah / def.embreeSah, 1.0, false});
    if (!inst) {
        targets.push_back({s, "[17] PREFER_FAST_BUILD, 1 thread >= 2x Embree LOW", fastBuild.embreeMs / fastBuild.vkasMs, 2.0, true});
        for (int k = 0; k < 3; ++k)
            targets.push_back({s, std::string("[17] PREFER_FAST_BUILD tracing, ") + rayKindName(RayKind(k)) + " >= 0.75x default build",
                               variantRate[2][k] / variantRate[0][k], 0.75, true});
        // torcs-forza: long thin triangles, where a better tree pays most; the scanned meshes: 5%.
        const double goal = s == "torcs-forza" ? 1.15 : 1.05;
        targets.push_back({s, "[17] PREFER_FAST_TRACE tracing, diffuse >= " + ratio(goal) + " default build",
                           variantRate[1][1] / variantRate[0][1], goal, true});
    }
    targets.push_back({s, "[17] PREFER_FAST_TRACE build, 1 thread >= Embree HIGH", fastTrace.embreeMs / fastTrace.vkasMs, 1.0, true});
    targets.push_back({s, std::string("[17] refit (MODE_UPDATE) >= Embree ") + refit.embreeName, refit.embreeMs / refit.vkasMs,
                       1.0, true});

    vkN.destroy(nTlas);
    vkN.destroy(nBlas);
    vk1.destroy(defaultTlas);
    if (inst) vk1.destroy(blas);
}

void Bench::runScaling(const Scene& sc, const std::vector<unsigned>& threadCounts,
                       VkBuildAccelerationStructureFlagsKHR flags) {
    const size_t tris = sc.mesh.triangleCount();
    const bool fastBuild = flags == VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR;
    const RTCBuildQuality quality = fastBuild ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM;
    std::printf("\ndeferred build scaling, %s (%zu triangles), %s, best of %d\n", sc.name.c_str(), tris,
                fastBuild ? "PREFER_FAST_BUILD / Embree LOW" : "default flags / Embree MEDIUM", o_.reps);
    std::printf("  %7s | %10s %8s %8s | %10s %8s %8s | %6s\n", "threads", "vkas ms", "Mtris/s", "speed-up", "Embree ms",
                "Mtris/s", "speed-up", "ratio");
    VkasEngine vk(1);
    double vk1 = 0, em1 = 0;
    json.begin(nullptr, '{').field("scene", sc.name).field("triangles", double(tris));
    json.field("build", fastBuild ? "PREFER_FAST_BUILD" : "default").begin("runs", '[');
    for (unsigned t : threadCounts) {
        VkasEngine::Build b = vk.buildBottom(sc.mesh, flags, o_.reps, t);
        vk.destroy(b.s);
        EmbreeEngine em(t);
        const double emMs = em.buildMesh(sc.mesh, quality, o_.reps).ms;
        if (t == threadCounts.front()) vk1 = b.ms * t, em1 = emMs * t;  // normalised to one thread
        std::printf("  %7u | %10.1f %8.2f %8.2f | %10.1f %8.2f %8.2f | %6s\n", t, b.ms, tris / b.ms / 1000, vk1 / b.ms, emMs,
                    tris / emMs / 1000, em1 / emMs, ratio(emMs / b.ms).c_str());
        json.begin(nullptr, '{').field("threads", double(t)).field("vkas_ms", b.ms).field("embree_ms", emMs).end('}');
        if (t == 16 && threadCounts.front() == 1 && !fastBuild) {
            targets.push_back({sc.name, "[17] deferred build, 16 joined threads >= 12x one thread", vk1 / b.ms, 12.0, true});
            targets.push_back({sc.name, "[17] deferred build, 16 threads >= 1.5x Embree MEDIUM on 16", emMs / b.ms, 1.5, true});
        }
    }
    json.end(']').end('}');
}

}  // namespace

int main(int argc, char** argv) {
    Options o;
    CLI::App app{"vkas_bench_embree: vkas against Embree 3 on the same meshes and rays (builds, traversal, agreement, scaling)"};
    app.add_option("--scene", o.scenes, "named scenes (see --list); default: all, or bunny and instances with --quick");
    app.add_option("--mesh", o.meshes, "mesh files assimp reads (.obj, .off, .3ds, .ac, .ply, ...)");
    bool list = false;
    app.add_flag("--list", list, "list the named scenes and exit");
    app.add_option("--threads", o.threads, "threads for the all-threads traversal runs (default: hardware threads)")
        ->check(CLI::Range(1u, 1024u));
    app.add_option("--rays", o.rays, "rays of each kind (default 2^20; 2^15 with --quick)");
    app.add_option("--reps", o.reps, "repetitions, best taken (default 3; 1 with --quick)")->check(CLI::Range(1, 100));
    app.add_option("--instances", o.instances, "instances in the 'instances' scene (default 10000; 1024 with --quick)");
    app.add_option("--threads-list", o.threadsList, "joined-thread counts of the scaling runs (default 1,2,4,8,16; 1,2 with --quick)");
    app.add_option("--scaling-scene", o.scalingScenes,
                   "scenes of the scaling runs (default bunny-4m; bunny with --quick; e.g. bunny-4m bunny-16m)");
    app.add_option("--scale", o.scaleTriangles,
                   "a scale run: a mesh of at least this many triangles (copies of bunny-4m) built on all threads by "
                   "vkas and Embree MEDIUM, traced, time and peak memory per triangle (e.g. 100000000)");
    app.add_flag("--no-scaling", o.noScaling, "skip the deferred-build scaling runs");
    app.add_option("--show-disagreements", o.showDisagreements,
                   "print every ray where vkas and Embree differ (or the first N of each kind), with both hits and the "
                   "oracle's verdict")
        ->expected(0, 1)
        ->default_str("all")
        ->check([](const std::string& v) {
            return v == "all" || (!v.empty() && v.find_first_not_of("0123456789") == std::string::npos)
                       ? std::string()
                       : std::string("expects a count or 'all'");
        });
    app.add_option("--json", o.json, "write the results as JSON to this file");
    app.add_option("--dump-hits", o.dumpHits,
                   "write every ray's one-thread vkasTraceRays result (every scene and ray kind of the run) to this "
                   "binary file, for --compare-hits in another build");
    app.add_option("--compare-hits", o.compareHits,
                   "compare this run's one-thread vkasTraceRays results with those of a file --dump-hits wrote (same "
                   "options); exits non-zero when a ray differs other than by a tie");
    app.add_option("--data-dir", o.dataDir, "where scripts/setup-bench.sh extracted the CGAL meshes");
    app.add_flag("--quick", o.quick, "a short smoke run: the bunny and a small instance scene, few rays, one repetition");
    CLI11_PARSE(app, argc, argv);
    if (list) {
        for (const SceneInfo& s : sceneCatalogue()) std::printf("%-16s %s\n", s.name, s.what);
        return 0;
    }
    if (o.dataDir.empty()) {
        const char* env = std::getenv("VKAS_BENCH_DATA");
        const char* cache = std::getenv("XDG_CACHE_HOME");
        const char* home = std::getenv("HOME");
        o.dataDir = env ? env : cache ? std::string(cache) + "/vkas-bench" : std::string(home ? home : ".") + "/.cache/vkas-bench";
    }
    if (o.rays == 0) o.rays = o.quick ? (1u << 15) : (1u << 20);
    if (o.reps == 0) o.reps = o.quick ? 1 : 3;
    if (o.instances == 0) o.instances = o.quick ? 1024 : 10000;
    if (o.threadsList.empty()) o.threadsList = o.quick ? "1,2" : "1,2,4,8,16";
    if (o.scalingScenes.empty()) o.scalingScenes = {o.quick ? "bunny" : "bunny-4m"};
    if (o.scenes.empty() && o.meshes.empty()) {
        if (o.quick) o.scenes = {"bunny", "instances"};
        else
            for (const SceneInfo& s : sceneCatalogue())
                if (std::string(s.name) != "bunny-16m") o.scenes.push_back(s.name);
    }
    std::vector<unsigned> threadCounts;
    {
        std::stringstream ss(o.threadsList);
        std::string item;
        while (std::getline(ss, item, ',')) threadCounts.push_back(unsigned(std::stoul(item)));
    }

    Bench bench(o);
    Json& j = bench.json;
    try {
        std::error_code ec;
        if (!o.dumpHits.empty() && !o.compareHits.empty() &&
            (o.dumpHits == o.compareHits || std::filesystem::equivalent(o.dumpHits, o.compareHits, ec)))
            throw std::runtime_error("--dump-hits and --compare-hits name the same file");
        if (!o.compareHits.empty()) {
            bench.compare = std::make_unique<HitFileReader>(o.compareHits);
        }
        if (!o.dumpHits.empty()) {
            char writer[256];
            std::snprintf(writer, sizeof writer, "vkas %d.%d.%d, Embree %d.%d.%d; %zu rays per kind, %u instances%s",
                          VKAS_VERSION_MAJOR, VKAS_VERSION_MINOR, VKAS_VERSION_PATCH, RTC_VERSION_MAJOR, RTC_VERSION_MINOR,
                          RTC_VERSION_PATCH, o.rays, o.instances, o.quick ? ", --quick" : "");
            bench.dump = std::make_unique<HitFileWriter>(o.dumpHits, writer);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vkas_bench_embree: %s\n", e.what());
        return 2;
    }
    std::printf("vkas_bench_embree: vkas %d.%d.%d against Embree %d.%d.%d; %u hardware threads; all-threads runs on %u; "
                "%zu rays per kind; best of %d%s\n",
                VKAS_VERSION_MAJOR, VKAS_VERSION_MINOR, VKAS_VERSION_PATCH, RTC_VERSION_MAJOR, RTC_VERSION_MINOR,
                RTC_VERSION_PATCH, std::thread::hardware_concurrency(), o.threads, o.rays, o.reps, o.quick ? " (--quick)" : "");
    if (bench.compare)
        std::printf("comparing hits with %s (written by: %s)\n", o.compareHits.c_str(), bench.compare->writer().c_str());
    std::printf("builds on one thread (vkas: no deferral; Embree: threads=1); ratios are vkas / Embree (speed: Embree ms / vkas ms)\n");
    j.begin(nullptr, '{').field("vkas_version", std::to_string(VKAS_VERSION_MAJOR) + "." + std::to_string(VKAS_VERSION_MINOR));
    j.field("embree_version", std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
                                  std::to_string(RTC_VERSION_PATCH));
    j.field("hardware_threads", double(std::thread::hardware_concurrency())).field("threads", double(o.threads));
    j.field("rays_per_kind", double(o.rays)).field("reps", double(o.reps)).field("quick", o.quick);
    int status = 0;
    try {
        j.begin("scenes", '[');
        for (const std::string& s : o.scenes) bench.runScene(makeScene(s, false, o.dataDir, o.instances));
        for (const std::string& m : o.meshes) bench.runScene(makeScene(m, true, o.dataDir, o.instances));
        j.end(']');
        if (!o.noScaling) {
            j.begin("scaling", '[');
            for (const std::string& name : o.scalingScenes) {
                const Scene sc = makeScene(name, false, o.dataDir, o.instances);
                for (const auto flags : {VkBuildAccelerationStructureFlagsKHR(0),
                                         VkBuildAccelerationStructureFlagsKHR(VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR)})
                    bench.runScaling(sc, threadCounts, flags);
            }
            j.end(']');
        }
        if (o.scaleTriangles) runScaleRun(o.scaleTriangles, o.threads, o.rays, o.dataDir, j);
        if (bench.dump) {
            bench.dump->finish();
            std::printf("\nhits written to %s\n", o.dumpHits.c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vkas_bench_embree: %s\n", e.what());
        return 1;
    }
    if (bench.compare) {
        j.begin("hit_comparison", '{').field("file", o.compareHits).field("writer", bench.compare->writer());
        j.field("different", double(bench.hitsDifferent)).field("not_compared_rays_differ", double(bench.hitsRefused));
        j.begin("not_in_this_run", '[');
        std::string absent;
        for (const HitFileReader::Section& s : bench.compare->sections())
            if (!s.used) {
                absent += " " + s.scene + "/" + rayKindName(s.kind);
                j.begin(nullptr, '{').field("scene", s.scene).field("rays", rayKindName(s.kind)).end('}');
            }
        j.end(']').end('}');
        std::printf("\nhits against %s: %zu rays differ (not ties)%s", o.compareHits.c_str(), bench.hitsDifferent,
                    bench.hitsRefused ? "" : "\n");
        if (bench.hitsRefused) std::printf("; %zu scene/kind(s) NOT COMPARED: their rays differ\n", bench.hitsRefused);
        if (!absent.empty()) std::printf("  in the file, not in this run:%s\n", absent.c_str());
        if (bench.hitsDifferent || bench.hitsRefused) status = 1;
    }
    std::printf("\ntargets (issue 15; [17]: issue 17)%s:\n", o.quick ? " -- a --quick run is a smoke test, not a measurement" : "");
    j.begin("targets", '[');
    size_t missed = 0;
    for (const Target& t : bench.targets) {
        const bool met = t.higherIsBetter ? t.value >= t.goal : t.value <= t.goal;
        missed += !met;
        char verdict[96];
        if (met) std::snprintf(verdict, sizeof verdict, "met");
        else if (t.higherIsBetter) std::snprintf(verdict, sizeof verdict, "MISSED by %.0f%% (needs %.2fx more)", 100 * (1 - t.value / t.goal), t.goal / t.value);
        else std::snprintf(verdict, sizeof verdict, "MISSED by %.0f%%", 100 * (t.value / t.goal - 1));
        std::printf("  %-14s %-64s %7.2f (goal %s%.2f)  %s\n", t.scene.c_str(), t.what.c_str(), t.value,
                    t.higherIsBetter ? ">=" : "<=", t.goal, verdict);
        j.begin(nullptr, '{').field("scene", t.scene).field("target", t.what).field("value", t.value).field("goal", t.goal);
        j.field("higher_is_better", t.higherIsBetter).field("met", met).end('}');
    }
    j.end(']').end('}');
    std::printf("  %zu of %zu targets missed\n", missed, bench.targets.size());
    if (!o.json.empty()) {
        std::ofstream(o.json) << j.str() << "\n";
        std::printf("JSON written to %s\n", o.json.c_str());
    }
    return status;
}
