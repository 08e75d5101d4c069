#include "render_command.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "as_builder.hpp"
#include "build_preference.hpp"
#include "heatmap_command.hpp"
#include "input_error.hpp"
#include "progress.hpp"
#include "png_writer.hpp"
#include "renderer.hpp"
#include "scene.hpp"
#include "vk_context.hpp"

namespace vkas_tool {
namespace {

double mib(double bytes) { return bytes / (1024.0 * 1024.0); }

double rate(double count, double ms) { return ms > 0 ? count / (ms * 1000.0) : 0.0; }  // millions per second

}  // namespace

int runRender(const RenderCommandOptions& options) {
    if (options.heatmap) {
        HeatmapOptions h;
        h.files = options.files;
        h.output = options.output == "vkas-render.png" ? "vkas-heatmap.png" : options.output;
        h.metric = options.metric;
        h.width = options.width, h.height = options.height;
        h.view = options.view;
        h.preference = options.preference;
        h.threads = options.threads;
        h.validation = options.validation;
        return runHeatmap(h);
    }
    const VkBuildAccelerationStructureFlagsKHR flags = preferenceFlags(options.preference);
    // Rays, hits and surfaces of one chunk, and the image: refuse sizes that cannot fit before allocating them.
    const double pixels = double(options.width) * options.height;
    checkMemory(pixels * (sizeof(VkasRay) + sizeof(VkasHit) + 3) +
                    std::min(pixels, double(1u << 20)) * (options.aoSamples + 1) * (sizeof(VkasRay) + sizeof(VkasHit)),
                "an image of " + std::to_string(options.width) + "x" + std::to_string(options.height));
    DeviceOptions deviceOptions;
    deviceOptions.validation = options.validation;
    deviceOptions.workerThreads = options.threads;
    VkContext ctx(deviceOptions);
    uint32_t threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());

    auto t0 = std::chrono::steady_clock::now();
    Scene scene;
    if (options.files.empty()) {
        SceneOptions sceneOptions;
        sceneOptions.instanceCount = options.instances;
        sceneOptions.seed = options.seed;
        scene = makeBuiltinScene(sceneOptions);
    } else {
        FileScene fs = loadFileScene(options.files, options.view, float(options.width) / float(options.height));
        scene = std::move(fs.scene);
        Progress::clear();
        for (const ModelInfo& m : fs.models)
            std::printf("loaded %s: %u meshes, %u instances, %llu triangles, %llu vertices\n", m.path.c_str(), m.meshes,
                        m.instances, static_cast<unsigned long long>(m.triangles),
                        static_cast<unsigned long long>(m.vertices));
        std::printf("bounds (%g, %g, %g) .. (%g, %g, %g); camera at (%g, %g, %g)\n", fs.bounds.lo.x, fs.bounds.lo.y,
                    fs.bounds.lo.z, fs.bounds.hi.x, fs.bounds.hi.y, fs.bounds.hi.z, scene.camera.position.x,
                    scene.camera.position.y, scene.camera.position.z);
    }
    double sceneMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("vkas render: %s, %ux%u, %u AO rays per pixel, %u trace threads, %s build, validation %s\n",
                options.files.empty() ? "built-in scene" : "files", options.width, options.height, options.aoSamples,
                threads, options.preference.c_str(), options.validation ? "on" : "off");
    std::printf("scene: %zu meshes %s in %.1f ms\n", scene.meshes.size(), options.files.empty() ? "generated" : "loaded",
                sceneMs);

    Progress::note("building");
    auto blas = buildBottomLevel(ctx, scene.blases, flags);
    std::printf("\nbottom level: %zu structures built in one vkBuildAccelerationStructuresKHR call\n",
                blas->handles.size());
    std::printf("  %-12s %-16s %10s %10s %12s %10s %14s\n", "structure", "primitives", "geometries", "count",
                "size (bytes)", "bytes/prim", "scratch (bytes)");
    static const char* const kKinds[] = {"triangles", "spheres", "swept spheres", "procedural boxes"};
    for (size_t i = 0; i < blas->stats.size(); ++i) {
        const StructureStats& s = blas->stats[i];
        const BlasDesc& d = scene.blases[i];
        std::printf("  %-12s %-16s %10zu %10llu %12llu %10.1f %14llu\n", s.name.c_str(),
                    kKinds[static_cast<int>(d.kind)], d.kind == PrimitiveKind::Triangles ? d.geometries.size() : 1,
                    static_cast<unsigned long long>(s.primitives), static_cast<unsigned long long>(s.size),
                    s.primitives ? static_cast<double>(s.size) / s.primitives : 0.0,
                    static_cast<unsigned long long>(s.buildScratchSize));
    }
    const uint64_t tris = blas->totalPrimitives();
    std::printf("  %-12s %-16s %10s %10llu %12llu %10.1f %14llu\n", "total", "", "",
                static_cast<unsigned long long>(tris), static_cast<unsigned long long>(blas->totalSize()),
                tris ? static_cast<double>(blas->totalSize()) / tris : 0.0,
                static_cast<unsigned long long>(blas->scratchBytes));
    std::printf("  build %.2f ms (%.2f Mprims/s, one thread), sizes query %.3f ms, input data %.2f MiB\n",
                blas->buildMs, rate(static_cast<double>(tris), blas->buildMs), blas->sizeQueryMs,
                mib(static_cast<double>(blas->inputBytes)));

    auto tlas = buildTopLevel(ctx, scene.instances, blas->handles, flags);
    Progress::clear();
    const StructureStats& ts = tlas->stats[0];
    std::printf("\ntop level: %llu instances, %llu bytes (%.1f bytes/instance), scratch %llu bytes\n",
                static_cast<unsigned long long>(ts.primitives), static_cast<unsigned long long>(ts.size),
                ts.primitives ? static_cast<double>(ts.size) / ts.primitives : 0.0,
                static_cast<unsigned long long>(ts.buildScratchSize));
    std::printf("  build %.3f ms (%.2f Minstances/s, one thread)\n", tlas->buildMs,
                rate(static_cast<double>(ts.primitives), tlas->buildMs));
    std::printf("  %llu triangles seen through the instances\n",
                static_cast<unsigned long long>(scene.instancedTriangles()));

    RenderOptions renderOptions;
    renderOptions.width = options.width;
    renderOptions.height = options.height;
    renderOptions.aoSamples = options.aoSamples;
    RenderStats stats;
    Image image;
    {
        Progress progress("tracing", static_cast<uint64_t>(pixels));
        renderOptions.progress = [&](uint64_t done, uint64_t) { progress.update(done); };
        image = render(ctx, scene, tlas->handles[0], renderOptions, stats);
    }
    std::printf("\ntrace (vkasTraceRaysProcedural: crates intersected by the renderer, %u threads)\n", threads);
    std::printf("  primary    %10llu rays %9.1f ms %8.2f Mrays/s  (closest hit, %.1f%% hit)\n",
                static_cast<unsigned long long>(stats.primaryRays), stats.primaryMs,
                rate(static_cast<double>(stats.primaryRays), stats.primaryMs),
                stats.primaryRays ? 100.0 * stats.primaryHits / stats.primaryRays : 0.0);
    std::printf("  occlusion  %10llu rays %9.1f ms %8.2f Mrays/s  (any hit: AO within %.1f + sun shadow, %.1f%% hit)\n",
                static_cast<unsigned long long>(stats.occlusionRays), stats.occlusionMs,
                rate(static_cast<double>(stats.occlusionRays), stats.occlusionMs), scene.aoRadius,
                stats.occlusionRays ? 100.0 * stats.occlusionHits / stats.occlusionRays : 0.0);
    std::printf("  render total %.1f ms (ray generation and shading on one thread included)\n", stats.totalMs);

    std::error_code ec;
    std::filesystem::path parent = std::filesystem::path(options.output).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent, ec);  // writePng reports what still fails
    writePng(options.output, image.width, image.height, image.rgb);
    auto where = std::filesystem::absolute(options.output, ec);
    std::printf("\nwrote %s (%ux%u)\n", ec ? options.output.c_str() : where.c_str(), image.width, image.height);
    if (ctx.validationMessages() != 0) {
        std::fprintf(stderr, "vkas render: %u validation messages\n", ctx.validationMessages());
        return 1;
    }
    return 0;
}

}  // namespace vkas_tool
