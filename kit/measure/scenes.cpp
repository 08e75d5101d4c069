#include "scenes.hpp"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <filesystem>
#include <random>
#include <stdexcept>
#include <unordered_map>

namespace vb {

Box meshBounds(const Mesh& m) {
    Box b;
    for (size_t i = 0; i < m.vertexCount(); ++i) b.grow(&m.vertices[3 * i]);
    return b;
}

Box transformBox(const Box& b, const Transform& x) {
    Box r;
    for (int c = 0; c < 8; ++c) {
        const double p[3] = {(c & 1) ? b.hi[0] : b.lo[0], (c & 2) ? b.hi[1] : b.lo[1], (c & 4) ? b.hi[2] : b.lo[2]};
        float q[3];
        for (int k = 0; k < 3; ++k)
            q[k] = float(x[4 * k] * p[0] + x[4 * k + 1] * p[1] + x[4 * k + 2] * p[2] + x[4 * k + 3]);
        r.grow(q);
    }
    return r;
}

Box sceneBounds(const Scene& s) {
    const Box m = meshBounds(s.mesh);
    if (!s.manyInstances()) return m;
    Box r;
    for (const Transform& x : s.instances) r.grow(transformBox(m, x));
    return r;
}

Mesh loadMesh(const std::string& path) {
    Assimp::Importer importer;
    importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    const aiScene* s = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                   aiProcess_PreTransformVertices | aiProcess_SortByPType);
    if (!s) throw std::runtime_error("assimp cannot read " + path + ": " + importer.GetErrorString());
    Mesh m;
    for (unsigned i = 0; i < s->mNumMeshes; ++i) {
        const aiMesh* am = s->mMeshes[i];
        const uint32_t base = uint32_t(m.vertexCount());
        for (unsigned v = 0; v < am->mNumVertices; ++v)
            m.vertices.insert(m.vertices.end(), {am->mVertices[v].x, am->mVertices[v].y, am->mVertices[v].z});
        for (unsigned f = 0; f < am->mNumFaces; ++f) {
            const aiFace& face = am->mFaces[f];
            if (face.mNumIndices != 3) continue;
            m.indices.insert(m.indices.end(),
                             {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
        }
    }
    if (m.indices.empty()) throw std::runtime_error(path + " holds no triangles");
    m.vertices.push_back(0);  // padding for Embree's 16-byte loads
    return m;
}

Mesh subdivide(const Mesh& m) {
    Mesh r;
    r.vertices.assign(m.vertices.begin(), m.vertices.begin() + 3 * m.vertexCount());
    std::unordered_map<uint64_t, uint32_t> midpoints;
    midpoints.reserve(m.indices.size());
    auto mid = [&](uint32_t a, uint32_t b) {
        const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
        auto [it, added] = midpoints.try_emplace(key, uint32_t(r.vertices.size() / 3));
        if (added)
            for (int k = 0; k < 3; ++k) r.vertices.push_back(0.5f * (m.vertices[3 * a + k] + m.vertices[3 * b + k]));
        return it->second;
    };
    r.indices.reserve(4 * m.indices.size());
    for (size_t t = 0; t < m.triangleCount(); ++t) {
        const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
        const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
        r.indices.insert(r.indices.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
    }
    r.vertices.push_back(0);
    return r;
}

const std::vector<SceneInfo>& sceneCatalogue() {
    static const std::vector<SceneInfo> scenes = {
        {"bunny", "Stanford bunny, glmark2-data models/bunny.obj (69,666 triangles)"},
        {"bunny-1m", "the bunny after 2 midpoint subdivisions (1,114,656 triangles)"},
        {"bunny-4m", "the bunny after 3 midpoint subdivisions (4,458,624 triangles)"},
        {"bunny-16m", "the bunny after 4 midpoint subdivisions (17,834,496 triangles; scaling runs, not in the default list)"},
        {"cgal-elephant", "CGAL data/meshes/refined_elephant.off (libcgal-demo, 88,928 triangles)"},
        {"cgal-armadillo", "CGAL data/meshes/armadillo.off (libcgal-demo, 52,000 triangles)"},
        {"torcs-forza", "TORCS road track forza.acc (torcs-data): long thin road and wall triangles"},
        {"instances", "many instances of the bunny on a jittered grid (top-level builds)"},
    };
    return scenes;
}

namespace {

const char* kBunny = "/usr/share/glmark2/models/bunny.obj";
const char* kForza = "/usr/share/games/torcs/tracks/road/forza/forza.acc";

std::vector<Transform> instanceGrid(const Box& b, unsigned count) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    const unsigned side = unsigned(std::ceil(std::sqrt(double(count))));
    const float step = 1.2f * float(std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]}));
    std::vector<Transform> xs;
    for (unsigned i = 0; i < count; ++i) {
        const float angle = 6.2831853f * u(rng), s = 0.7f + 0.6f * u(rng);
        const float c = std::cos(angle) * s, sn = std::sin(angle) * s;
        const float tx = step * (float(i % side) + 0.3f * u(rng)), tz = step * (float(i / side) + 0.3f * u(rng));
        const float ty = 0.2f * step * u(rng);
        xs.push_back({c, 0, sn, tx, 0, s, 0, ty, -sn, 0, c, tz});  // rotation about y, scale, translation
    }
    return xs;
}

}  // namespace

Scene makeScene(const std::string& name, bool isPath, const std::string& dataDir, unsigned instanceCount) {
    Scene s;
    s.name = name;
    if (isPath) {
        s.name = std::filesystem::path(name).stem().string();
        s.source = name;
        s.mesh = loadMesh(name);
        return s;
    }
    if (name == "bunny" || name == "bunny-1m" || name == "bunny-4m" || name == "bunny-16m" || name == "instances") {
        s.source = kBunny;
        s.mesh = loadMesh(kBunny);
        const int levels = name == "bunny-1m" ? 2 : name == "bunny-4m" ? 3 : name == "bunny-16m" ? 4 : 0;
        for (int k = 0; k < levels; ++k) s.mesh = subdivide(s.mesh);
        if (name == "instances") s.instances = instanceGrid(meshBounds(s.mesh), instanceCount);
    } else if (name == "cgal-elephant" || name == "cgal-armadillo") {
        s.source = dataDir + "/cgal/data/meshes/" + (name == "cgal-elephant" ? "refined_elephant.off" : "armadillo.off");
        s.mesh = loadMesh(s.source);
    } else if (name == "torcs-forza") {
        s.source = kForza;
        s.mesh = loadMesh(kForza);
        s.thin = true;
    } else {
        throw std::runtime_error("unknown scene " + name + " (see --list)");
    }
    return s;
}

}  // namespace vb
