#include "model_loader.hpp"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <thread>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <utility>
#include <vector>

#include "imported_scene_check.hpp"
#include "input_error.hpp"
#include "mesh_header_check.hpp"
#include "structure_file.hpp"

namespace vkas_tool {
namespace {

namespace fs = std::filesystem;

// Some importers repair what they find wrong and only log it (assimp's OFF reader clamps an out-of-range vertex
// index to the last vertex): the first error assimp logs while reading a file fails the load.
class ErrorCatcher : public Assimp::LogStream {
public:
    void write(const char* message) override {
        if (first.empty() && message) {
            first = message;
            while (!first.empty() && (first.back() == '\n' || first.back() == '\r')) first.pop_back();
            const size_t colon = first.find(": ");  // "Error, T0: OFF: ..." -> "OFF: ..."
            if (first.rfind("Error", 0) == 0 && colon != std::string::npos) first = first.substr(colon + 2);
        }
    }
    std::string first;
};

struct AssimpErrorLog {
    AssimpErrorLog() {
        Assimp::DefaultLogger::create("", Assimp::Logger::NORMAL, 0);  // no default streams: nothing printed
        Assimp::DefaultLogger::get()->attachStream(&catcher, Assimp::Logger::Err);
    }
    ~AssimpErrorLog() {
        Assimp::DefaultLogger::get()->detachStream(&catcher, Assimp::Logger::Err);
        Assimp::DefaultLogger::kill();
    }
    ErrorCatcher catcher;
};

// The checks assimp would report vaguely ("No suitable reader found") or not at all, done first.
uint64_t checkReadableFile(const std::string& path) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw InputError(path, "no such file");
    if (fs::is_directory(st)) throw InputError(path, "is a directory, not a file");
    if (!fs::is_regular_file(st)) throw InputError(path, "is not a regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, std::string("cannot be read: ") + std::strerror(errno));
    const uint64_t size = fs::file_size(path, ec);
    if (ec) throw InputError(path, "cannot be read: " + ec.message());
    if (size == 0) throw InputError(path, "is empty");
    return size;
}

Affine toAffine(const aiMatrix4x4& m) {
    Affine a;
    const float rows[3][4] = {{m.a1, m.a2, m.a3, m.a4}, {m.b1, m.b2, m.b3, m.b4}, {m.c1, m.c2, m.c3, m.c4}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) a.m[r][c] = rows[r][c];
    return a;
}

bool finite(const Affine& a) {
    for (const auto& row : a.m)
        for (float v : row)
            if (!std::isfinite(v)) return false;
    return true;
}

Vec3 albedoOf(const aiMaterial* material) {
    aiColor4D c;
    if (material && material->Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS && std::isfinite(c.r) &&
        std::isfinite(c.g) && std::isfinite(c.b)) {
        const Vec3 v{std::clamp(c.r, 0.0f, 1.0f), std::clamp(c.g, 0.0f, 1.0f), std::clamp(c.b, 0.0f, 1.0f)};
        if (v.x + v.y + v.z > 0.15f) return v;  // black or unset diffuse: files that rely on textures
    }
    return {0.72f, 0.70f, 0.66f};
}

// The mesh's triangles, checked: finite vertices, indices inside the vertex array. Points and lines are dropped.
Mesh convertMesh(const std::string& path, const aiMesh& am, unsigned index) {
    const std::string which = "mesh " + std::to_string(index) + (am.mName.length ? " (\"" + std::string(am.mName.C_Str()) + "\")" : "");
    Mesh m;
    m.name = am.mName.C_Str();
    uint64_t triangles = 0;
    for (unsigned f = 0; f < am.mNumFaces; ++f) triangles += am.mFaces[f].mNumIndices == 3;
    if (triangles == 0) return m;
    checkMemory(double(am.mNumVertices) * 24.0 + double(triangles) * 12.0, path + ": " + which);
    m.positions.reserve(am.mNumVertices);
    for (unsigned v = 0; v < am.mNumVertices; ++v) {
        const aiVector3D& p = am.mVertices[v];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            throw InputError(path, which + ": vertex " + std::to_string(v) + " is not finite (" + std::to_string(p.x) +
                                       ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")");
        m.positions.push_back({p.x, p.y, p.z});
    }
    m.indices.reserve(3 * triangles);
    for (unsigned f = 0; f < am.mNumFaces; ++f) {
        const aiFace& face = am.mFaces[f];
        if (face.mNumIndices != 3) continue;
        for (int k = 0; k < 3; ++k) {
            if (face.mIndices[k] >= am.mNumVertices)
                throw InputError(path, which + ": face " + std::to_string(f) + " uses vertex " +
                                           std::to_string(face.mIndices[k]) + ", but the mesh has " +
                                           std::to_string(am.mNumVertices) + " vertices");
            m.indices.push_back(face.mIndices[k]);
        }
    }
    m.computeNormals();
    return m;
}

// assimp's importers themselves crash on some damaged files (inside Importer::ReadFile, before anything of vkas sees
// the data: found by vkas_fuzz_mesh_file). So a child process reads the file first; when it dies, the file is
// refused and this process never reads it. Reading is deterministic: a file the child read is read here the same way.
void readInChild(const std::string& path, uint64_t fileSize) {
    std::fflush(nullptr);
    const pid_t pid = fork();
    if (pid < 0) return;  // no child: read in this process as before
    if (pid == 0) {
        const int null = open("/dev/null", O_WRONLY);  // what glibc or a sanitizer prints as it dies: not ours
        if (null >= 0) dup2(null, 1), dup2(null, 2);
        try {
            Assimp::Importer importer;
            importer.ReadFile(path, 0);
        } catch (...) {
        }
        _exit(0);
    }
    // Some importers also loop forever on a damaged file: the child gets 10 s, and 1 s more per MiB of file.
    const auto limit = std::chrono::steady_clock::now() + std::chrono::seconds(10 + fileSize / 1048576);
    int status = 0;
    for (;;) {
        const pid_t done = waitpid(pid, &status, WNOHANG);
        if (done == pid) break;
        if (done < 0 && errno != EINTR) return;
        if (std::chrono::steady_clock::now() > limit) {
            kill(pid, SIGKILL);
            waitpid(pid, &status, 0);
            throw InputError(path, "damaged: assimp's importer did not finish reading it in " +
                                       std::to_string(10 + fileSize / 1048576) + " s");
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (WIFSIGNALED(status))
        throw InputError(path, "damaged: assimp's importer crashed reading it (signal " + std::to_string(WTERMSIG(status)) + ")");
    if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
        throw InputError(path, "damaged: assimp's importer failed reading it (exit status " +
                                   std::to_string(WEXITSTATUS(status)) + ")");
}

}  // namespace

ModelInfo loadModel(const std::string& path, Scene& scene) {
    const uint64_t fileSize = checkReadableFile(path);
    if (looksSerialized(path))
        throw InputError(path, "is a serialized acceleration structure, not a mesh (`vkas inspect` reads it)");
    checkDeclaredCounts(path, fileSize);
    checkMemory(8.0 * double(fileSize), "loading " + path);  // assimp holds the file and its own copy of the meshes

    readInChild(path, fileSize);
    Assimp::Importer importer;
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* s = nullptr;
    AssimpErrorLog errors;
    auto failed = [&] {
        std::string why = importer.GetErrorString();
        if (why.find("bad_alloc") != std::string::npos) throw InputError(path, "out of memory while reading it");
        if (why.find("No meshes remaining") != std::string::npos)  // what assimp says once points and lines are gone
            throw InputError(path, "holds no triangles (only points or lines)");
        throw InputError(path, "not a mesh file assimp can read: " + (why.empty() ? std::string("unknown error") : why));
    };
    // Read with no post-processing step: the steps trust what the importer made, and a truncated or damaged file
    // makes faces of garbage indices (SIGSEGV in Triangulate) or polygon claims without polygons (Triangulate's
    // assertion aborts). checkImportedScene checks the scene first and makes the steps' preconditions true.
    try {
        s = importer.ReadFile(path, 0);
    } catch (const std::bad_alloc&) {
        throw InputError(path, "out of memory while reading it");
    }
    if (!s) failed();
    if (!errors.catcher.first.empty()) throw InputError(path, "malformed: " + errors.catcher.first);
    checkImportedScene(path, importer);
    try {
        s = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
    } catch (const std::bad_alloc&) {
        throw InputError(path, "out of memory while reading it");
    }
    if (!s) failed();
    if (!errors.catcher.first.empty()) throw InputError(path, "malformed: " + errors.catcher.first);
    if (!s->mRootNode || s->mNumMeshes == 0) throw InputError(path, "holds no meshes");

    ModelInfo info;
    info.path = path;
    const uint32_t firstMaterial = static_cast<uint32_t>(scene.materials.size());
    for (unsigned i = 0; i < std::max(1u, s->mNumMaterials); ++i)
        scene.materials.push_back({albedoOf(i < s->mNumMaterials ? s->mMaterials[i] : nullptr)});

    // One bottom level per mesh with triangles; blasOf[i] = its index in scene.blases, or -1.
    std::vector<int64_t> blasOf(s->mNumMeshes, -1);
    for (unsigned i = 0; i < s->mNumMeshes; ++i) {
        Mesh m = convertMesh(path, *s->mMeshes[i], i);
        if (m.indices.empty()) continue;
        info.triangles += m.triangleCount();
        info.vertices += m.positions.size();
        scene.meshes.push_back(std::make_unique<Mesh>(std::move(m)));
        BlasDesc blas;
        blas.name = scene.meshes.back()->name.empty() ? "mesh " + std::to_string(i) : scene.meshes.back()->name;
        blas.geometries.push_back({scene.meshes.back().get(), VertexLayout::Float3, VK_INDEX_TYPE_UINT32, {},
                                   VK_GEOMETRY_OPAQUE_BIT_KHR});
        blasOf[i] = static_cast<int64_t>(scene.blases.size());
        scene.blases.push_back(std::move(blas));
        ++info.meshes;
    }
    if (info.meshes == 0) throw InputError(path, "holds no triangles (only points or lines)");

    // The node tree, depth first with an explicit stack (a deep hierarchy must not overflow ours).
    std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{s->mRootNode, s->mRootNode->mTransformation}};
    while (!stack.empty()) {
        auto [node, world] = stack.back();
        stack.pop_back();
        const Affine transform = toAffine(world);
        for (unsigned k = 0; k < node->mNumMeshes; ++k) {
            const unsigned mesh = node->mMeshes[k];
            if (mesh >= s->mNumMeshes || blasOf[mesh] < 0) continue;
            if (!finite(transform))
                throw InputError(path, "node \"" + std::string(node->mName.C_Str()) + "\" has a non-finite transform");
            // An instance transform must be invertible (VUID-VkTransformMatrixKHR-matrix-03799: vkas refuses the
            // build otherwise); the same determinant in double precision.
            const auto& m = transform.m;
            const double det = double(m[0][0]) * (double(m[1][1]) * m[2][2] - double(m[1][2]) * m[2][1]) -
                               double(m[0][1]) * (double(m[1][0]) * m[2][2] - double(m[1][2]) * m[2][0]) +
                               double(m[0][2]) * (double(m[1][0]) * m[2][1] - double(m[1][1]) * m[2][0]);
            if (!(det != 0.0 && std::isfinite(det)))
                throw InputError(path, "node \"" + std::string(node->mName.C_Str()) + "\" has a transform that is not invertible");
            InstanceDesc inst;
            inst.blas = static_cast<uint32_t>(blasOf[mesh]);
            inst.transform = transform;
            inst.customIndex = firstMaterial + std::min(s->mMeshes[mesh]->mMaterialIndex, std::max(1u, s->mNumMaterials) - 1);
            // Files disagree on winding and many meshes are open: shade both sides.
            inst.flags = VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR;
            scene.instances.push_back(inst);
            ++info.instances;
        }
        for (unsigned c = node->mNumChildren; c-- > 0;)
            if (node->mChildren[c]) stack.push_back({node->mChildren[c], world * node->mChildren[c]->mTransformation});
    }
    if (info.instances == 0) throw InputError(path, "no node of the file places its meshes");
    return info;
}

Box instancedBounds(const Scene& scene) {
    constexpr float inf = std::numeric_limits<float>::infinity();
    Box b{{inf, inf, inf}, {-inf, -inf, -inf}};
    for (const InstanceDesc& inst : scene.instances) {
        const BlasDesc& blas = scene.blases.at(inst.blas);
        for (const GeometryDesc& g : blas.geometries) {
            const Affine x = g.transform ? inst.transform * *g.transform : inst.transform;
            for (const Vec3& p : g.mesh->positions) {
                const Vec3 w = x.point(p);
                b.lo = {std::min(b.lo.x, w.x), std::min(b.lo.y, w.y), std::min(b.lo.z, w.z)};
                b.hi = {std::max(b.hi.x, w.x), std::max(b.hi.y, w.y), std::max(b.hi.z, w.z)};
            }
        }
    }
    return b;
}

}  // namespace vkas_tool
