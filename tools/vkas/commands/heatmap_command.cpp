#include "heatmap_command.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "as_builder.hpp"
#include "build_preference.hpp"
#include "camera_rays.hpp"
#include "cost_tracer.hpp"
#include "heatmap_image.hpp"
#include "input_error.hpp"
#include "json_writer.hpp"
#include "png_writer.hpp"
#include "progress.hpp"

namespace vkas_tool {
namespace {

struct Summary {
    uint32_t min = 0, max = 0;
    double mean = 0;
    uint64_t total = 0;
};

Summary summarise(const std::vector<uint32_t>& v) {
    Summary s;
    if (v.empty()) return s;
    s.min = *std::min_element(v.begin(), v.end());
    s.max = *std::max_element(v.begin(), v.end());
    for (uint32_t x : v) s.total += x;
    s.mean = double(s.total) / double(v.size());
    return s;
}

void writeCounts(const std::string& path, uint32_t W, uint32_t H, const std::vector<uint32_t>& nodes,
                 const std::vector<uint32_t>& prims, const std::vector<uint32_t>& insts) {
    FILE* f = std::fopen(path.c_str(), "w");
    if (!f) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
    std::fprintf(f, "# vkas heatmap counts: %u x %u pixels, rows top to bottom; nodes primitives instances\n", W, H);
    for (size_t p = 0; p < nodes.size(); ++p) std::fprintf(f, "%u %u %u\n", nodes[p], prims[p], insts[p]);
    if (std::fclose(f) != 0) throw std::runtime_error("cannot write " + path);
}

void jsonSummary(JsonWriter& j, const char* key, const Summary& s) {
    j.beginObject(key).value("min", s.min).value("mean", s.mean).value("max", s.max).value("total", s.total).end();
}

}  // namespace

int runHeatmap(HeatmapOptions o) {
    if (o.metric != "nodes" && o.metric != "primitives")
        throw std::invalid_argument("--metric " + o.metric + ": expected nodes or primitives");
    if (o.files.empty()) throw std::invalid_argument("heatmap: give a mesh file");
    const size_t pixels = size_t(o.width) * o.height;
    checkMemory(double(pixels) * (sizeof(VkasRay) + sizeof(VkasHit) + 3 * 4 + 3), "a heatmap of " +
                std::to_string(o.width) + "x" + std::to_string(o.height));
    DeviceOptions deviceOptions;
    deviceOptions.validation = o.validation;
    deviceOptions.workerThreads = o.threads;
    VkContext ctx(deviceOptions);
    const unsigned threads = o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency());

    o.view.ground = false;  // the cost of the file's own trees
    FileScene fs = loadFileScene(o.files, o.view, float(o.width) / float(o.height));
    const VkBuildAccelerationStructureFlagsKHR flags = preferenceFlags(o.preference);
    Progress::note("building");
    auto blas = buildBottomLevel(ctx, fs.scene.blases, flags);
    auto tlas = buildTopLevel(ctx, fs.scene.instances, blas->handles, flags);
    Progress::clear();

    const std::vector<VkasRay> rays = primaryRays(fs.scene.camera, o.width, o.height, fs.scene.rayTMax);
    std::vector<const unsigned char*> bottomOfInstance;
    for (const InstanceDesc& inst : fs.scene.instances) bottomOfInstance.push_back(blas->block(inst.blas));
    const CostTracer tracer(tlas->block(0), std::move(bottomOfInstance));

    // Counting traversal: rows handed out to the threads; each pixel's counts depend on its ray only.
    std::vector<uint32_t> nodes(pixels), prims(pixels), insts(pixels);
    std::vector<CostHit> costHits(pixels);
    std::atomic<uint32_t> nextRow{0}, rowsDone{0};
    auto t0 = std::chrono::steady_clock::now();
    auto work = [&] {
        for (uint32_t y; (y = nextRow.fetch_add(1)) < o.height; ++rowsDone)
            for (uint32_t x = 0; x < o.width; ++x) {
                const size_t p = size_t(y) * o.width + x;
                TraceCounters c;
                costHits[p] = tracer.trace(rays[p], c);
                nodes[p] = c.nodes, prims[p] = c.primitives, insts[p] = c.instances;
            }
    };
    {
        Progress progress("counting traversal", pixels);
        std::vector<std::thread> pool;
        for (unsigned k = 1; k < threads; ++k) pool.emplace_back(work);
        if (Progress::enabled() && threads > 1) {  // this thread reports; the others trace
            while (rowsDone.load() < o.height) {
                progress.update(uint64_t(rowsDone.load()) * o.width);
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
            }
        } else {
            work();
        }
        for (auto& t : pool) t.join();
    }
    const double countMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

    // The same rays through vkas: the counting traversal must find the hits vkas finds.
    std::vector<VkasHit> hits(pixels);
    check(vkasTraceRays(ctx.device(), tlas->handles[0], VKAS_TRACE_MODE_CLOSEST_HIT, VKAS_RAY_FLAG_NONE, 0xFF,
                        uint32_t(pixels), rays.data(), hits.data()),
          "vkasTraceRays");
    uint64_t agree = 0, vkasHits = 0;
    for (size_t p = 0; p < pixels; ++p) {
        const bool vh = hits[p].type != VKAS_COMMITTED_INTERSECTION_NONE;
        vkasHits += vh;
        if (vh != costHits[p].hit) continue;
        if (!vh || std::fabs(hits[p].t - costHits[p].t) <= 1e-4f * std::max(1.0f, hits[p].t)) ++agree;
    }

    const Summary ns = summarise(nodes), ps = summarise(prims), is = summarise(insts);
    const Summary& shown = o.metric == "nodes" ? ns : ps;
    const Image img = heatmapImage(o.metric == "nodes" ? nodes : prims, o.width, o.height, shown.min, shown.max);
    writePng(o.output, img.width, img.height, img.rgb);
    if (!o.countsFile.empty()) writeCounts(o.countsFile, o.width, o.height, nodes, prims, insts);

    if (o.json) {
        JsonWriter j;
        j.beginObject().value("output", o.output).value("metric", o.metric).value("width", o.width).value("height", o.height);
        j.value("pixels", uint64_t(pixels)).value("preference", o.preference);
        jsonSummary(j, "nodes", ns);
        jsonSummary(j, "primitives", ps);
        jsonSummary(j, "instances", is);
        j.beginObject("agreement").value("pixels", uint64_t(pixels)).value("agree", agree).value("vkasHits", vkasHits).end();
        j.value("countMs", countMs).end();
        std::printf("%s\n", j.str().c_str());
    } else {
        std::printf("vkas heatmap: %zu files, %ux%u, %s build, colour = %s\n", o.files.size(), o.width, o.height,
                    o.preference.c_str(), o.metric == "nodes" ? "internal nodes visited" : "triangles tested");
        std::printf("  nodes visited per ray     min %u  mean %.2f  max %u\n", ns.min, ns.mean, ns.max);
        std::printf("  triangles tested per ray  min %u  mean %.2f  max %u\n", ps.min, ps.mean, ps.max);
        std::printf("  instances tested per ray  min %u  mean %.2f  max %u\n", is.min, is.mean, is.max);
        std::printf("  hits agree with vkasTraceRays on %llu of %zu pixels (%llu hits); counted in %.1f ms, %u threads\n",
                    static_cast<unsigned long long>(agree), pixels, static_cast<unsigned long long>(vkasHits), countMs,
                    threads);
        std::printf("wrote %s (%ux%u, legend %u .. %u)\n", o.output.c_str(), img.width, img.height, shown.min, shown.max);
    }
    if (ctx.validationMessages() != 0) return 1;
    return 0;
}

}  // namespace vkas_tool
