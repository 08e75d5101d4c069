#include "imported_scene_check.hpp"

#include <assimp/Importer.hpp>
#include <assimp/scene.h>

#include <cmath>
#include <cstdint>
#include <unordered_set>
#include <utility>
#include <vector>

#include "input_error.hpp"

namespace vkas_tool {
namespace {

constexpr size_t kMaxNodeDepth = 10000;  // assimp's own steps and its destructor recurse over the node tree

std::string meshName(const aiMesh& m, unsigned index) {
    std::string s = "mesh " + std::to_string(index);
    if (m.mName.length) s += " (\"" + std::string(m.mName.C_Str()) + "\")";
    return s;
}

bool finite(const aiVector3D& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// Replaces every polygon of more than kMaxEarCutCorners corners by the fan of triangles from its first corner.
void fanLargePolygons(const std::string& path, const std::string& which, aiMesh& m) {
    uint64_t faces = 0;
    bool any = false;
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
        const unsigned n = m.mFaces[f].mNumIndices;
        any |= n > kMaxEarCutCorners;
        faces += n > kMaxEarCutCorners ? n - 2 : 1;
    }
    if (!any) return;
    if (faces > UINT32_MAX) throw InputError(path, which + ": its polygons make more than 2^32 triangles");
    aiFace* out = new aiFace[faces];
    aiFace* next = out;
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
        aiFace& in = m.mFaces[f];
        if (in.mNumIndices <= kMaxEarCutCorners) {
            next->mNumIndices = in.mNumIndices;
            next->mIndices = in.mIndices;  // moved: the old face no longer owns it
            in.mIndices = nullptr;
            in.mNumIndices = 0;
            ++next;
            continue;
        }
        for (unsigned k = 1; k + 1 < in.mNumIndices; ++k, ++next) {
            next->mNumIndices = 3;
            next->mIndices = new unsigned[3]{in.mIndices[0], in.mIndices[k], in.mIndices[k + 1]};
        }
    }
    delete[] m.mFaces;
    m.mFaces = out;
    m.mNumFaces = static_cast<unsigned>(faces);
}

void checkMesh(const std::string& path, aiMesh& m, unsigned index) {
    const std::string which = meshName(m, index);
    if (m.mNumFaces && !m.mFaces) throw InputError(path, which + ": " + std::to_string(m.mNumFaces) + " faces announced, none stored");
    if (m.mNumVertices && !m.mVertices)
        throw InputError(path, which + ": " + std::to_string(m.mNumVertices) + " vertices announced, no positions stored");
    unsigned types = 0;
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
        const aiFace& face = m.mFaces[f];
        if (face.mNumIndices == 0 || !face.mIndices)
            throw InputError(path, which + ": face " + std::to_string(f) + " has no vertex indices");
        for (unsigned k = 0; k < face.mNumIndices; ++k) {
            const unsigned v = face.mIndices[k];
            if (v >= m.mNumVertices)
                throw InputError(path, which + ": face " + std::to_string(f) + " uses vertex " + std::to_string(v) +
                                           ", out of range: the mesh has " + std::to_string(m.mNumVertices) + " vertices");
        }
        types |= face.mNumIndices == 1   ? aiPrimitiveType_POINT
                 : face.mNumIndices == 2 ? aiPrimitiveType_LINE
                 : face.mNumIndices == 3 ? aiPrimitiveType_TRIANGLE
                                         : aiPrimitiveType_POLYGON;
    }
    // JoinIdenticalVertices sorts every vertex of a mesh with triangles by its position (std::sort: a NaN breaks the
    // order it needs).
    if (types & (aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON))
        for (unsigned v = 0; v < m.mNumVertices; ++v)
            if (!finite(m.mVertices[v])) {
                const aiVector3D& p = m.mVertices[v];
                throw InputError(path, which + ": vertex " + std::to_string(v) + " is not finite (" + std::to_string(p.x) +
                                           ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")");
            }
    // JoinIdenticalVertices renumbers the vertices that bone weights and morph targets refer to.
    if (m.mNumBones && !m.mBones) throw InputError(path, which + ": its bones are missing");
    for (unsigned b = 0; b < m.mNumBones; ++b) {
        const aiBone* bone = m.mBones[b];
        if (!bone || (bone->mNumWeights && !bone->mWeights))
            throw InputError(path, which + ": bone " + std::to_string(b) + " is missing or has no weights");
        for (unsigned w = 0; w < bone->mNumWeights; ++w)
            if (bone->mWeights[w].mVertexId >= m.mNumVertices)
                throw InputError(path, which + ": bone " + std::to_string(b) + " weighs vertex " +
                                           std::to_string(bone->mWeights[w].mVertexId) + ", out of range: the mesh has " +
                                           std::to_string(m.mNumVertices) + " vertices");
    }
    if (m.mNumAnimMeshes && !m.mAnimMeshes) throw InputError(path, which + ": its morph targets are missing");
    for (unsigned a = 0; a < m.mNumAnimMeshes; ++a) {
        const aiAnimMesh* am = m.mAnimMeshes[a];
        if (!am || am->mNumVertices != m.mNumVertices)
            throw InputError(path, which + ": morph target " + std::to_string(a) + " does not have the mesh's " +
                                       std::to_string(m.mNumVertices) + " vertices");
    }
    // The types the faces have: an importer's claim of polygons a mesh does not hold makes Triangulate assert.
    m.mPrimitiveTypes = types;
    if (types & aiPrimitiveType_POLYGON) fanLargePolygons(path, which, m);
}

// Every node reached once, at most kMaxNodeDepth deep, placing meshes the scene has.
void checkNodes(const std::string& path, Assimp::Importer& importer, const aiScene& s) {
    std::unordered_set<const aiNode*> seen;
    std::vector<std::pair<const aiNode*, size_t>> stack{{s.mRootNode, 1}};
    while (!stack.empty()) {
        auto [node, depth] = stack.back();
        stack.pop_back();
        const std::string name = "node \"" + std::string(node->mName.C_Str()) + "\"";
        if (!seen.insert(node).second) {
            (void)importer.GetOrphanedScene();  // freeing a node twice would crash: leave the scene alive
            throw InputError(path, name + " is reached twice: the node hierarchy is not a tree");
        }
        if (depth > kMaxNodeDepth)
            throw InputError(path, "the node hierarchy is more than " + std::to_string(kMaxNodeDepth) + " levels deep");
        if (node->mNumMeshes && !node->mMeshes) throw InputError(path, name + ": its mesh list is missing");
        for (unsigned k = 0; k < node->mNumMeshes; ++k)
            if (node->mMeshes[k] >= s.mNumMeshes)
                throw InputError(path, name + " places mesh " + std::to_string(node->mMeshes[k]) + ", but the file has " +
                                           std::to_string(s.mNumMeshes) + " meshes");
        if (node->mNumChildren && !node->mChildren) throw InputError(path, name + ": its children are missing");
        for (unsigned c = 0; c < node->mNumChildren; ++c) {
            if (!node->mChildren[c]) throw InputError(path, name + ": child " + std::to_string(c) + " is missing");
            stack.push_back({node->mChildren[c], depth + 1});
        }
    }
}

}  // namespace

void checkImportedScene(const std::string& path, Assimp::Importer& importer) {
    aiScene* s = const_cast<aiScene*>(importer.GetScene());  // the steps assimp runs next modify it the same way
    if (!s || !s->mRootNode || s->mNumMeshes == 0 || !s->mMeshes) throw InputError(path, "holds no meshes");
    if (s->mNumMaterials && !s->mMaterials) throw InputError(path, "its materials are missing");
    for (unsigned i = 0; i < s->mNumMeshes; ++i) {
        if (!s->mMeshes[i]) throw InputError(path, "mesh " + std::to_string(i) + " is missing");
        checkMesh(path, *s->mMeshes[i], i);
    }
    checkNodes(path, importer, *s);
}

}  // namespace vkas_tool
