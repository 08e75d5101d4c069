// vkas: command-line tool for the vkas library.
//   vkas render [FILE...]  trace the built-in scene or mesh files (AO and shadows), write a PNG, print statistics
//   vkas inspect FILE      what a structure (built from a mesh, or a serialized blob) holds: sizes, histograms, SAH
//   vkas heatmap FILE...   the traversal cost of every pixel as an image, with its minimum, mean and maximum
//   vkas bench FILE...     build, refit, compaction and trace rates (beside Embree when built with it)
//   vkas info              the device's features, limits, vertex formats and commands
// Exit status: 0 success, 1 bad input or a failure it explains, 2 a Vulkan call that failed.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "bench_command.hpp"
#include "build_preference.hpp"
#include "heatmap_command.hpp"
#include "info_command.hpp"
#include "input_error.hpp"
#include "inspect_command.hpp"
#include "progress.hpp"
#include "render_command.hpp"
#include "vk_context.hpp"

namespace {

using namespace vkas_tool;

void addViewOptions(CLI::App* cmd, ViewOptions& view, std::string& up) {
    cmd->add_option("--camera", view.camera, "Camera as eye,target,up: 9 comma-separated numbers (default: framed on the bounds)");
    cmd->add_option("--fov", view.fovDegrees, "Vertical field of view in degrees")->capture_default_str()->check(CLI::Range(1.0f, 170.0f));
    cmd->add_option("--up", up, "The files' up axis: y or z")->capture_default_str()->check(CLI::IsMember({"y", "z"}));
}

void addPreference(CLI::App* cmd, std::string& preference) {
    cmd->add_option("--preference", preference, "Build preference: default, fast-trace or fast-build")
        ->capture_default_str()
        ->check(CLI::IsMember(preferenceNames()));
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"vkas: Vulkan acceleration structures and ray queries on the host.\n"
                 "Render, inspect, heatmap and bench work on mesh files (OBJ, PLY, STL, OFF, glTF/GLB, 3DS, AC3D and\n"
                 "whatever else assimp reads); inspect also reads structures serialized by vkas."};
    app.set_version_flag("--version", std::to_string(VKAS_VERSION_MAJOR) + "." + std::to_string(VKAS_VERSION_MINOR) +
                                          "." + std::to_string(VKAS_VERSION_PATCH));
    app.require_subcommand(1);
    bool quiet = false, noValidation = false;
    app.add_flag("-q,--quiet", quiet, "No progress display (it is shown only on a terminal anyway)");
    app.add_flag("--no-validation", noValidation, "Create the device with validation disabled");
    app.fallthrough();

    RenderCommandOptions render;
    std::string renderUp = "y";
    CLI::App* renderCmd = app.add_subcommand(
        "render", "Trace the built-in scene, or mesh files (one bottom level per mesh, a top level over the node "
                  "transforms), with ambient occlusion and shadows, and write a PNG image");
    renderCmd->add_option("files", render.files, "Mesh files (none: the built-in scene)");
    renderCmd->add_option("-o,--output", render.output, "Output PNG file")->capture_default_str();
    renderCmd->add_option("--width", render.width, "Image width in pixels")->capture_default_str()->check(CLI::Range(1u, 16384u));
    renderCmd->add_option("--height", render.height, "Image height in pixels")->capture_default_str()->check(CLI::Range(1u, 16384u));
    renderCmd->add_option("--spp,--ao-samples", render.aoSamples, "Ambient-occlusion rays per pixel")
        ->capture_default_str()
        ->check(CLI::Range(0u, 1024u));
    renderCmd->add_option("--threads", render.threads, "Worker threads for vkasTraceRays (0: all cores)")
        ->capture_default_str()
        ->check(CLI::Range(0u, 1024u));
    addPreference(renderCmd, render.preference);
    addViewOptions(renderCmd, render.view, renderUp);
    renderCmd->add_flag("--no-ground", [&](int64_t) { render.view.ground = false; }, "Files: no ground quad under the meshes");
    renderCmd->add_flag("--heatmap", render.heatmap, "Draw the traversal cost per pixel instead (see `vkas heatmap`)");
    renderCmd->add_option("--metric", render.metric, "With --heatmap: nodes or primitives")
        ->capture_default_str()
        ->check(CLI::IsMember({"nodes", "primitives"}));
    renderCmd->add_option("--instances", render.instances, "Built-in scene: scattered instances")
        ->capture_default_str()
        ->check(CLI::Range(0u, 10000000u));
    renderCmd->add_option("--seed", render.seed, "Built-in scene: seed of the random placement")->capture_default_str();

    InspectOptions inspect;
    std::vector<std::string> boxes;
    CLI::App* inspectCmd = app.add_subcommand(
        "inspect", "Report what a structure holds: FILE is a mesh (built into one bottom level) or a structure "
                   "serialized by vkas (loaded and integrity-checked)");
    inspectCmd->add_option("file", inspect.file, "Mesh file, or serialized structure")->required();
    inspectCmd->add_flag("--json", inspect.json, "Print the report as JSON");
    inspectCmd->add_option("--boxes", boxes, "LEVEL OUT.obj: write the boxes of one tree level (0: the root node's children) as an OBJ")
        ->expected(2);
    inspectCmd->add_option("--write-blob", inspect.writeBlob, "Also serialize the structure to this file");
    addPreference(inspectCmd, inspect.preference);

    HeatmapOptions heatmap;
    std::string heatmapUp = "y";
    CLI::App* heatmapCmd = app.add_subcommand(
        "heatmap", "Draw the traversal cost of each pixel's camera ray (nodes visited or triangles tested) with a "
                   "legend, and print its minimum, mean and maximum");
    heatmapCmd->add_option("files", heatmap.files, "Mesh files")->required();
    heatmapCmd->add_option("-o,--output", heatmap.output, "Output PNG file")->capture_default_str();
    heatmapCmd->add_option("--metric", heatmap.metric, "nodes (internal nodes visited) or primitives (triangles tested)")
        ->capture_default_str()
        ->check(CLI::IsMember({"nodes", "primitives"}));
    heatmapCmd->add_option("--width", heatmap.width, "Image width in pixels")->capture_default_str()->check(CLI::Range(1u, 16384u));
    heatmapCmd->add_option("--height", heatmap.height, "Image height in pixels")->capture_default_str()->check(CLI::Range(1u, 16384u));
    heatmapCmd->add_option("--threads", heatmap.threads, "Threads (0: all cores)")->capture_default_str()->check(CLI::Range(0u, 1024u));
    heatmapCmd->add_flag("--json", heatmap.json, "Print the statistics as JSON");
    heatmapCmd->add_option("--counts", heatmap.countsFile, "Write every pixel's counts to this text file");
    addPreference(heatmapCmd, heatmap.preference);
    addViewOptions(heatmapCmd, heatmap.view, heatmapUp);

    BenchOptions bench;
    CLI::App* benchCmd = app.add_subcommand(
        "bench", "Build (each preference), refit, compaction and trace rates (camera, diffuse, shadow rays; one and all "
                 "threads) of the files' triangles, beside Embree when the tool was built with it");
    benchCmd->add_option("files", bench.files, "Mesh files (their triangles are benchmarked as one mesh)")->required();
    benchCmd->add_option("--threads", bench.threads, "The \"all threads\" count (0: all cores)")->capture_default_str()->check(CLI::Range(0u, 1024u));
    benchCmd->add_option("--rays", bench.rays, "Rays of each kind")->capture_default_str()->check(CLI::Range(1u, 1u << 26));
    benchCmd->add_option("--reps", bench.reps, "Repetitions (the best is reported)")->capture_default_str()->check(CLI::Range(1, 1000));
    benchCmd->add_flag("--json", bench.json, "Print the table as JSON");
    benchCmd->add_flag("--no-embree", [&](int64_t) { bench.embree = false; }, "Measure vkas only");

    InfoOptions info;
    CLI::App* infoCmd = app.add_subcommand("info", "Print the device's features, limits, vertex formats and commands");
    infoCmd->add_flag("--all-formats", info.allFormats, "Also list the formats that are not vertex formats");

    CLI11_PARSE(app, argc, argv);
    Progress::configure(quiet);
    render.validation = inspect.validation = heatmap.validation = !noValidation;
    render.view.up = renderUp[0];
    heatmap.view.up = heatmapUp[0];
    if (boxes.size() == 2) {
        try {
            size_t used = 0;
            inspect.boxesLevel = std::stoll(boxes[0], &used);
            if (used != boxes[0].size() || inspect.boxesLevel < 0 || inspect.boxesLevel > 64) throw std::invalid_argument("");
        } catch (const std::exception&) {
            std::fprintf(stderr, "vkas: error: --boxes LEVEL OUT.obj: \"%s\" is not a level (0 to 64)\n", boxes[0].c_str());
            return 1;
        }
        inspect.boxesFile = boxes[1];
    }

    try {
        if (renderCmd->parsed()) return runRender(render);
        if (inspectCmd->parsed()) return runInspect(inspect);
        if (heatmapCmd->parsed()) return runHeatmap(heatmap);
        if (benchCmd->parsed()) return runBench(bench);
        if (infoCmd->parsed()) return runInfo(info);
    } catch (const InputError& e) {
        Progress::clear();
        std::fprintf(stderr, "vkas: error: %s\n", e.what());
        return 1;
    } catch (const VkError& e) {
        Progress::clear();
        std::fprintf(stderr, "vkas: error: %s\n", e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        Progress::clear();
        std::fprintf(stderr, "vkas: error: out of memory (the input is too large for this machine)\n");
        return 1;
    } catch (const std::exception& e) {
        Progress::clear();
        std::fprintf(stderr, "vkas: error: %s\n", e.what());
        return 1;
    }
    return 1;
}
