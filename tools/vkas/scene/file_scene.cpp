#include "file_scene.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "progress.hpp"

namespace vkas_tool {
namespace {

// A square of 2 x 2 cells at height `h` on the up axis, spanning `half` around `c`.
void addGround(Scene& scene, Vec3 c, float half, float h, char up) {
    Mesh quad;
    quad.name = "ground";
    auto corner = [&](float a, float b) {
        return up == 'z' ? Vec3{c.x + a * half, c.y + b * half, h} : Vec3{c.x + a * half, h, c.z + b * half};
    };
    quad.positions = {corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1)};
    quad.indices = {0, 2, 1, 0, 3, 2};
    quad.computeNormals();
    scene.meshes.push_back(std::make_unique<Mesh>(std::move(quad)));
    BlasDesc blas;
    blas.name = "ground";
    blas.geometries.push_back({scene.meshes.back().get(), VertexLayout::Float3, VK_INDEX_TYPE_UINT32, {},
                               VK_GEOMETRY_OPAQUE_BIT_KHR});
    scene.blases.push_back(std::move(blas));
    scene.materials.push_back({{0.80f, 0.80f, 0.78f}});
    InstanceDesc inst;
    inst.blas = static_cast<uint32_t>(scene.blases.size() - 1);
    inst.customIndex = static_cast<uint32_t>(scene.materials.size() - 1);
    inst.flags = VK_GEOMETRY_INSTANCE_TRIANGLE_FACING_CULL_DISABLE_BIT_KHR;
    scene.instances.push_back(inst);
}

}  // namespace

void parseCamera(const std::string& spec, Camera& camera) {
    std::vector<float> v;
    std::stringstream in(spec);
    std::string item;
    while (std::getline(in, item, ',')) {
        size_t used = 0;
        float f = 0;
        try {
            f = std::stof(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || !std::isfinite(f)) throw std::invalid_argument("--camera: \"" + item + "\" is not a number");
        v.push_back(f);
    }
    if (v.size() != 9) throw std::invalid_argument("--camera wants 9 numbers: eye x,y,z, target x,y,z, up x,y,z");
    camera.position = {v[0], v[1], v[2]};
    camera.target = {v[3], v[4], v[5]};
    camera.up = {v[6], v[7], v[8]};
    if (length(camera.target - camera.position) == 0 || length(cross(camera.target - camera.position, camera.up)) == 0)
        throw std::invalid_argument("--camera: the eye must differ from the target and the up vector from the view");
}

FileScene loadFileScene(const std::vector<std::string>& files, const ViewOptions& view, float aspect) {
    FileScene fs;
    for (const std::string& f : files) {
        Progress::note("loading " + f);
        fs.models.push_back(loadModel(f, fs.scene));
    }
    fs.bounds = instancedBounds(fs.scene);
    const Box& b = fs.bounds;
    const Vec3 centre = (b.lo + b.hi) * 0.5f;
    float radius = 0.5f * length(b.hi - b.lo);
    if (!(radius > 0) || !std::isfinite(radius)) radius = 1.0f;  // one point, or a flat triangle at one spot

    Scene& s = fs.scene;
    const bool zUp = view.up == 'z';
    s.camera.verticalFovDegrees = view.fovDegrees;
    s.camera.up = zUp ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
    // The camera sits above and in front, far enough that the bounding sphere fits the narrower field of view.
    const float halfV = view.fovDegrees * std::numbers::pi_v<float> / 360.0f;
    const float halfNarrow = std::min(halfV, std::atan(std::tan(halfV) * std::min(aspect, 1.0f)));
    const Vec3 back = normalize(zUp ? Vec3{0.5f, -1.0f, 0.6f} : Vec3{0.5f, 0.6f, 1.0f});
    const float distance = 1.05f * radius / std::sin(halfNarrow);
    s.camera.target = centre;
    s.camera.position = centre + back * distance;
    if (!view.camera.empty()) parseCamera(view.camera, s.camera);

    s.sunDirection = normalize(zUp ? Vec3{0.45f, -0.35f, 0.8f} : Vec3{0.45f, 0.8f, 0.35f});
    s.aoRadius = 0.3f * radius;
    s.fogDensity = 0.0f;
    s.rayTMax = std::max(1.0e4f, 100.0f * (distance + radius + length(s.camera.position - centre)));
    if (view.ground) addGround(s, centre, 4.0f * radius, (zUp ? b.lo.z : b.lo.y) - 1e-3f * radius, view.up);
    return fs;
}

}  // namespace vkas_tool
