// vkas: command-line tool for the vkas library.
//   vkas render   build the built-in scene, trace it, write a PNG, print statistics and timings
//   vkas info     print the device's features, limits, vertex formats and commands
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "info_command.hpp"
#include "render_command.hpp"
#include "vk_context.hpp"

int main(int argc, char** argv) {
    using namespace vkas_tool;
    CLI::App app{"vkas: Vulkan acceleration structures and ray queries on the host"};
    app.set_version_flag("--version", std::to_string(VKAS_VERSION_MAJOR) + "." + std::to_string(VKAS_VERSION_MINOR) +
                                          "." + std::to_string(VKAS_VERSION_PATCH));
    app.require_subcommand(1);

    RenderCommandOptions render;
    CLI::App* renderCmd = app.add_subcommand("render", "Build the built-in scene, trace it and write a PNG image");
    renderCmd->add_option("-o,--output", render.output, "Output PNG file")->capture_default_str();
    renderCmd->add_option("--width", render.width, "Image width in pixels")
        ->capture_default_str()
        ->check(CLI::Range(1u, 16384u));
    renderCmd->add_option("--height", render.height, "Image height in pixels")
        ->capture_default_str()
        ->check(CLI::Range(1u, 16384u));
    renderCmd->add_option("--spp,--ao-samples", render.aoSamples, "Ambient-occlusion rays per pixel")
        ->capture_default_str()
        ->check(CLI::Range(0u, 1024u));
    renderCmd->add_option("--threads", render.threads, "Worker threads for vkasTraceRays (0: all cores)")
        ->capture_default_str()
        ->check(CLI::Range(0u, 1024u));
    renderCmd->add_option("--instances", render.instances, "Scattered instances in the scene")
        ->capture_default_str()
        ->check(CLI::Range(0u, 10000000u));
    renderCmd->add_option("--seed", render.seed, "Seed of the scene's random placement")->capture_default_str();
    bool noValidation = false;
    renderCmd->add_flag("--no-validation", noValidation, "Create the device with validation disabled");

    InfoOptions info;
    CLI::App* infoCmd = app.add_subcommand("info", "Print the device's features, limits, vertex formats and commands");
    infoCmd->add_flag("--all-formats", info.allFormats, "Also list the formats that are not vertex formats");

    CLI11_PARSE(app, argc, argv);
    render.validation = !noValidation;

    try {
        if (renderCmd->parsed()) return runRender(render);
        if (infoCmd->parsed()) return runInfo(info);
    } catch (const VkError& e) {
        std::fprintf(stderr, "vkas: error: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "vkas: error: %s\n", e.what());
        return 1;
    }
    return 1;
}
