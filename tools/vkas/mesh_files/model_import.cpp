#include "model_import.hpp"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <new>
#include <utility>

#include "imported_scene_check.hpp"
#include "input_error.hpp"

namespace vkas_tool {
namespace {

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

Affine toAffine(const aiMatrix4x4& m) {
    Affine a;
    const float rows[3][4] = {{m.a1, m.a2, m.a3, m.a4}, {m.b1, m.b2, m.b3, m.b4}, {m.c1, m.c2, m.c3, m.c4}};
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) a.m[r][c] = rows[r][c];
    return a;
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

// The mesh's triangles as they are (the loader checks them); points and lines are dropped.
ImportedMesh copyTriangles(const std::string& path, const aiMesh& am, unsigned index) {
    ImportedMesh m;
    m.name = am.mName.C_Str();
    m.fileIndex = index;
    uint64_t triangles = 0;
    for (unsigned f = 0; f < am.mNumFaces; ++f) triangles += am.mFaces[f].mNumIndices == 3;
    if (triangles == 0) return m;
    checkMemory(double(am.mNumVertices) * 24.0 + double(triangles) * 12.0,
                path + ": mesh " + std::to_string(index));
    m.positions.reserve(am.mNumVertices);
    for (unsigned v = 0; v < am.mNumVertices; ++v) m.positions.push_back({am.mVertices[v].x, am.mVertices[v].y, am.mVertices[v].z});
    m.indices.reserve(3 * triangles);
    for (unsigned f = 0; f < am.mNumFaces; ++f)
        if (am.mFaces[f].mNumIndices == 3) m.indices.insert(m.indices.end(), am.mFaces[f].mIndices, am.mFaces[f].mIndices + 3);
    return m;
}

}  // namespace

ImportedModel importModel(const std::string& path) {
    Assimp::Importer importer;
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* s = nullptr;
    AssimpErrorLog errors;
    auto failed = [&] {
        std::string why = importer.GetErrorString();
        if (why.find("bad_alloc") != std::string::npos) throw std::bad_alloc();
        if (why.find("No meshes remaining") != std::string::npos)  // what assimp says once points and lines are gone
            throw InputError(path, "holds no triangles (only points or lines)");
        throw InputError(path, "not a mesh file assimp can read: " + (why.empty() ? std::string("unknown error") : why));
    };
    // Read with no post-processing step: the steps trust what the importer made, and a truncated or damaged file
    // makes faces of garbage indices (SIGSEGV in Triangulate) or polygon claims without polygons (Triangulate's
    // assertion aborts). checkImportedScene checks the scene first and makes the steps' preconditions true.
    s = importer.ReadFile(path, 0);
    if (!s) failed();
    if (!errors.catcher.first.empty()) throw InputError(path, "malformed: " + errors.catcher.first);
    checkImportedScene(path, importer);
    s = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
    if (!s) failed();
    if (!errors.catcher.first.empty()) throw InputError(path, "malformed: " + errors.catcher.first);
    if (!s->mRootNode || s->mNumMeshes == 0) throw InputError(path, "holds no meshes");

    ImportedModel model;
    for (unsigned i = 0; i < std::max(1u, s->mNumMaterials); ++i)
        model.albedos.push_back(albedoOf(i < s->mNumMaterials ? s->mMaterials[i] : nullptr));

    // The meshes with triangles; kept[i] = mesh i's place in model.meshes, or -1.
    std::vector<int64_t> kept(s->mNumMeshes, -1);
    for (unsigned i = 0; i < s->mNumMeshes; ++i) {
        ImportedMesh m = copyTriangles(path, *s->mMeshes[i], i);
        if (m.indices.empty()) continue;
        kept[i] = static_cast<int64_t>(model.meshes.size());
        model.meshes.push_back(std::move(m));
    }

    // The node tree, depth first with an explicit stack (a deep hierarchy must not overflow ours).
    std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{s->mRootNode, s->mRootNode->mTransformation}};
    while (!stack.empty()) {
        auto [node, world] = stack.back();
        stack.pop_back();
        for (unsigned k = 0; k < node->mNumMeshes; ++k) {
            const unsigned mesh = node->mMeshes[k];
            if (mesh >= s->mNumMeshes || kept[mesh] < 0) continue;
            ImportedInstance inst;
            inst.node = node->mName.C_Str();
            inst.mesh = static_cast<uint32_t>(kept[mesh]);
            inst.material = std::min(s->mMeshes[mesh]->mMaterialIndex, uint32_t(model.albedos.size()) - 1);
            inst.transform = toAffine(world);
            model.instances.push_back(std::move(inst));
        }
        for (unsigned c = node->mNumChildren; c-- > 0;)
            if (node->mChildren[c]) stack.push_back({node->mChildren[c], world * node->mChildren[c]->mTransformation});
    }
    return model;
}

}  // namespace vkas_tool
