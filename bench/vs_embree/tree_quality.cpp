// vkas_bench_tree_quality: how fast the trees of each build preference trace the same rays, on one thread, without
// Embree: for comparing builders (PREFER_FAST_TRACE against the default build, say) where timings are noisy. Prints
// each build's time, compacted bytes per triangle, SAH cost and the one-thread rates of camera, diffuse and shadow
// rays. Under `valgrind --tool=callgrind --toggle-collect='vb::measuredTrace*'` (one --kind) the instruction count
// of the trace alone is repeatable to the instruction, whatever else the machine runs. --engine embree traces the
// same rays with rtcIntersect1 / rtcOccluded1 (ROBUST scene, one thread) inside vb::measuredEmbree instead: with
// --validation (the default vkas device) this is what bench/vs_embree/count-instructions.sh compares (issue 36).
// The 'instances' scene is the bunny on a grid of --instances instances, in both engines (a top level over one
// bottom level); every other scene is one mesh under one identity instance.
//   vkas_bench_tree_quality --scene torcs-forza [--flags default fast-trace fast-build] [--rays N] [--kind diffuse]
//                           [--ray-query [--no-opaque]] [--denormals-are-zero] [--validation] [--engine vkas|embree]
//                           [--instances N]
#include <CLI/CLI.hpp>

#include <xmmintrin.h>

#include <cstdio>
#include <map>

#include "embree_side.hpp"
#include "rays.hpp"
#include "scenes.hpp"
#include "vkas_side.hpp"

namespace vb {

// The one trace that a callgrind run with --toggle-collect counts.
__attribute__((noinline)) double measuredTrace(VkasEngine& engine, VkAccelerationStructureKHR tlas, bool anyHit,
                                               const std::vector<VkasRay>& rays, std::vector<Hit>& hits, int reps) {
    return engine.traceBatch(tlas, anyHit, rays, hits, reps);
}

__attribute__((noinline)) double measuredEmbree(EmbreeEngine& embree, bool anyHit, bool coherent,
                                                const std::vector<VkasRay>& rays, std::vector<Hit>& hits, int reps) {
    return embree.trace(EmbreeCall::One, anyHit, coherent, rays, hits, 1, reps);
}

__attribute__((noinline)) double measuredQuery(VkasEngine& engine, VkAccelerationStructureKHR tlas, bool anyHit,
                                               const std::vector<VkasRay>& rays, std::vector<Hit>& hits, int reps,
                                               uint32_t extraFlags) {
    return engine.traceRayQuery(tlas, anyHit, rays, hits, reps, extraFlags);
}

}  // namespace vb

int main(int argc, char** argv) {
    using namespace vb;
    CLI::App app{"vkas_bench_tree_quality: the trees of vkas's build preferences, traced on one thread"};
    std::string sceneName = "bunny", dataDir;
    std::vector<std::string> flagNames{"default", "fast-trace"};
    std::vector<std::string> kinds{"camera", "diffuse", "shadow"};
    size_t rayCount = size_t(1) << 18;
    int reps = 3;
    bool denormalsAreZero = false, rayQuery = false, validation = false, noOpaque = false;
    std::string engineName = "vkas";
    app.add_option("--scene", sceneName, "a named scene of vkas_bench_embree (--list there)");
    app.add_option("--flags", flagNames, "build preferences: default, fast-trace, fast-build");
    app.add_option("--kind", kinds, "ray kinds: camera, diffuse, shadow");
    app.add_option("--rays", rayCount, "rays of each kind");
    app.add_option("--reps", reps, "repetitions, best taken");
    app.add_flag("--denormals-are-zero", denormalsAreZero,
                 "set MXCSR's flush-to-zero and denormals-are-zero bits on this thread first (a diagnostic: does a "
                 "tree's speed hang on denormal operands? with --ray-query, the traversal runs on this thread)");
    app.add_flag("--ray-query", rayQuery, "trace with vkasRayQuery* on this thread instead of vkasTraceRays");
    app.add_flag("--no-opaque", noOpaque,
                 "with --ray-query: the ray flag NoOpaque, so that every candidate goes to the application (which "
                 "drops it): the cost of queries over non-opaque geometry");
    app.add_flag("--validation", validation, "vkas: the default device (validation on), as users get it");
    app.add_option("--engine", engineName, "vkas, or embree: rtcIntersect1 / rtcOccluded1 on the same rays (ROBUST "
                   "scene of Embree's default quality; --flags and --ray-query do not apply)");
    app.add_option("--data-dir", dataDir, "where scripts/setup-bench.sh extracted the CGAL meshes");
    unsigned instanceCount = 10000;
    app.add_option("--instances", instanceCount,
                   "instances in the 'instances' scene (default 10000, as vkas_bench_embree): its top level is built "
                   "with each build preference over the default bottom level");
    CLI11_PARSE(app, argc, argv);
    if (dataDir.empty()) dataDir = std::string(getenv("HOME") ? getenv("HOME") : "/tmp") + "/.cache/vkas-bench";
    const std::map<std::string, VkBuildAccelerationStructureFlagsKHR> flagOf{
        {"default", 0},
        {"fast-trace", VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR},
        {"fast-build", VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR}};
    try {
        const Scene scene = makeScene(sceneName, false, dataDir, instanceCount);
        if (denormalsAreZero) _mm_setcsr(_mm_getcsr() | 0x8040);  // FTZ (bit 15) and DAZ (bit 6)
        if (engineName != "vkas" && engineName != "embree") throw std::runtime_error("unknown --engine " + engineName);
        VkasEngine engine(1, validation);
        // The rays, the same for every build: diffuse and shadow rays start at the default build's camera hits.
        const std::vector<VkasRay> camera = cameraRays(scene, rayCount);
        std::vector<Hit> cameraHits;
        {
            VkasEngine::Build blas = engine.buildBottom(scene.mesh, 0, 1);
            VkasEngine::Build tlas = engine.buildTop(scene.instances, blas.s.as, 0, 1);
            engine.traceBatch(tlas.s.as, false, camera, cameraHits, 1);
            engine.destroy(tlas.s), engine.destroy(blas.s);
        }
        std::map<std::string, std::vector<VkasRay>> rays{{"camera", camera}};
        rays["diffuse"] = secondaryRays(scene, RayKind::Diffuse, camera, cameraHits, rayCount);
        rays["shadow"] = secondaryRays(scene, RayKind::Shadow, camera, cameraHits, rayCount);
        std::printf("scene %s: %zu triangles, %zu rays of each kind, one thread\n", scene.name.c_str(),
                    scene.mesh.triangleCount(), rayCount);
        if (engineName == "embree") {
            EmbreeEngine embree(1);
            embree.makeTraceScene(scene);
            std::printf("  %-12s", "embree");
            for (const std::string& k : kinds) {
                if (!rays.count(k)) throw std::runtime_error("unknown --kind " + k);
                std::vector<Hit> hits;
                const double ms = measuredEmbree(embree, k == "shadow", k == "camera", rays[k], hits, reps);
                std::printf(" %s %.3f Mr/s", k.c_str(), double(rays[k].size()) / ms / 1000.0);
            }
            std::printf("\n");
            return 0;
        }
        std::printf("  %-12s %9s %8s %7s", "build", "ms", "B/tri", "SAH");
        for (const std::string& k : kinds) std::printf(" %9s", (k + " Mr/s").c_str());
        std::printf("\n");
        for (const std::string& f : flagNames) {
            if (!flagOf.count(f)) throw std::runtime_error("unknown --flags " + f);
            // (A scene of instances: the preference builds the bottom level; the top level is built by default.)
            VkasEngine::Build blas = engine.buildBottom(scene.mesh, flagOf.at(f), reps);
            VkasEngine::Build tlas = engine.buildTop(scene.instances, blas.s.as, 0, 1);
            std::printf("  %-12s %9.2f %8.1f %7.2f", f.c_str(), blas.ms,
                        double(blas.compactedSize) / double(scene.mesh.triangleCount()), engine.sah(blas.s).cost());
            for (const std::string& k : kinds) {
                if (!rays.count(k)) throw std::runtime_error("unknown --kind " + k);
                std::vector<Hit> hits;
                const double ms = rayQuery ? measuredQuery(engine, tlas.s.as, k == "shadow", rays[k], hits, reps,
                                                         noOpaque ? VKAS_RAY_FLAG_NO_OPAQUE : 0u)
                                          : measuredTrace(engine, tlas.s.as, k == "shadow", rays[k], hits, reps);
                std::printf(" %9.3f", double(rays[k].size()) / ms / 1000.0);
            }
            std::printf("\n");
            engine.destroy(tlas.s), engine.destroy(blas.s);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vkas_bench_tree_quality: %s\n", e.what());
        return 1;
    }
    return 0;
}
