// libFuzzer target over the vkas tool's mesh files (docs/FUZZING.md): the first byte picks the file's extension (OBJ,
// PLY, STL, OFF, glTF, GLB, 3DS: the formats docs/CLI.md names), the rest is the file. It goes through the tool's own
// loading code (tools/vkas/mesh_files/model_loader.cpp: the header check; in a child process assimp with no post-processing,
// the scene check of imported_scene_check.cpp and assimp's steps; the child's result decoded and checked), and what loads is built as `vkas render` builds it: one bottom
// level per mesh and a top level over the instances, through the public API with validation on.
//
// Checks (a failure aborts, which libFuzzer records as a crash):
//   - a refused file is an exception whose message names the file (the tool prints it and exits with status 1);
//   - a loaded scene holds only finite vertices, indices inside their mesh, whole triangles, instances of existing
//     bottom levels with finite transforms;
//   - the builds succeed and validation reports nothing about them.
#include <stdlib.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <memory>
#include <new>
#include <string>

#include "as_builder.hpp"
#include "fuzz_common.hpp"
#include "model_loader.hpp"
#include "vk_context.hpp"

namespace {

const char* const kExtensions[] = {"obj", "ply", "stl", "off", "gltf", "glb", "3ds"};

// A directory of this process for the input file, removed at exit.
struct TempDir {
    std::string dir;
    TempDir() {
        char name[] = "/tmp/vkas-fuzz-mesh.XXXXXX";
        if (!mkdtemp(name)) fz::fail("mkdtemp failed\n");
        dir = name;
    }
    ~TempDir() {
        for (const char* ext : kExtensions) std::remove((dir + "/input." + ext).c_str());
        rmdir(dir.c_str());
    }
};

bool finite(const vkas_tool::Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void checkScene(const vkas_tool::Scene& scene, const vkas_tool::ModelInfo& info) {
    FZ_CHECK(!scene.blases.empty() && !scene.instances.empty(), "a loaded file has %zu bottom levels, %zu instances",
             scene.blases.size(), scene.instances.size());
    uint64_t triangles = 0;
    for (const auto& mesh : scene.meshes) {
        FZ_CHECK(!mesh->indices.empty() && mesh->indices.size() % 3 == 0, "%zu indices", mesh->indices.size());
        for (uint32_t i : mesh->indices) FZ_CHECK(i < mesh->positions.size(), "index %u of %zu vertices", i, mesh->positions.size());
        for (const auto& p : mesh->positions) FZ_CHECK(finite(p), "a non-finite vertex was loaded");
        FZ_CHECK(mesh->normals.size() == mesh->positions.size(), "normals");
        triangles += mesh->triangleCount();
    }
    FZ_CHECK(triangles == info.triangles, "%llu triangles loaded, %llu reported", (unsigned long long)triangles,
             (unsigned long long)info.triangles);
    for (const auto& inst : scene.instances) {
        FZ_CHECK(inst.blas < scene.blases.size(), "instance of bottom level %u of %zu", inst.blas, scene.blases.size());
        for (const auto& row : inst.transform.m)
            for (float v : row) FZ_CHECK(std::isfinite(v), "a non-finite instance transform");
    }
}

}  // namespace

// The importer child is a fork of this process and keeps libFuzzer's allocation hook: one allocation past
// -malloc_limit_mb (run-fuzzers.sh: the RSS limit) ends it with libFuzzer's out-of-memory status, 71. assimp asks for
// such an allocation on a header that announces 2^31 list entries: that file is refused as out of memory, as the tool
// (where the allocation fails) refuses it, not reported as a sanitizer finding.
constexpr int kLibFuzzerOutOfMemoryExit = 71;

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    vkas_tool::setImporterOutOfMemoryExitStatus(kLibFuzzerOutOfMemoryExit);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static TempDir temp;
    static vkas_tool::VkContext ctx(vkas_tool::DeviceOptions{true, 1, true});
    if (size == 0) return 0;
    const std::string path = temp.dir + "/input." + kExtensions[data[0] % (sizeof kExtensions / sizeof *kExtensions)];
    {
        FILE* f = std::fopen(path.c_str(), "wb");
        if (!f || std::fwrite(data + 1, 1, size - 1, f) != size - 1 || std::fclose(f) != 0) fz::fail("cannot write %s\n", path.c_str());
    }

    vkas_tool::Scene scene;
    vkas_tool::ModelInfo info;
    try {
        info = vkas_tool::loadModel(path, scene);
    } catch (const std::bad_alloc&) {
        return 0;  // the tool reports "out of memory"
    } catch (const std::exception& e) {
        const std::string message = e.what();
        FZ_CHECK(message.find(path) != std::string::npos, "the message does not name the file: %s", e.what());
        FZ_CHECK(message.find('\n') == std::string::npos, "the message is not one line: %s", e.what());
        if (getenv("VKAS_FUZZ_VERBOSE")) std::fprintf(stderr, "refused: %s\n", e.what());
        return 0;
    }
    checkScene(scene, info);

    const uint32_t messages = ctx.validationMessages();
    try {
        const VkBuildAccelerationStructureFlagsKHR flags = vkas_tool::defaultBuildFlags();
        std::unique_ptr<vkas_tool::StructureSet> bottom = vkas_tool::buildBottomLevel(ctx, scene.blases, flags);
        std::unique_ptr<vkas_tool::StructureSet> top = vkas_tool::buildTopLevel(ctx, scene.instances, bottom->handles, flags);
        FZ_CHECK(top->stats.size() == 1 && top->stats[0].primitives == scene.instances.size(), "top level");
    } catch (const std::bad_alloc&) {
        return 0;
    } catch (const std::exception& e) {
        fz::fail("building a loaded file failed: %s\n", e.what());
    }
    FZ_CHECK(ctx.validationMessages() == messages, "validation reported: %s", ctx.lastMessage().c_str());
    return 0;
}
