// The Embree 3 side: scene builds at each build quality (timed rtcCommitScene, memory measured through the device's
// memory monitor), refits of a dynamic scene, the SAH cost of a user BVH built by rtcBuildBVH with the same quality,
// and traversal with rtcIntersect1/rtcOccluded1, the 8- and 16-ray packet calls and the ray-stream calls.
// The traced scene is RTC_SCENE_FLAG_ROBUST (watertight: the fair peer); a second one with Embree's default flags
// (not robust) is traced too, as a second column. The build rows use no scene flag, because Embree 3.13 ignores quality
// HIGH (no spatial splits) in a ROBUST scene. Vertex and index arrays are shared (not copied, not counted as Embree
// memory).
#pragma once

#include "common.hpp"
#include "sah.hpp"

#include <embree3/rtcore.h>

namespace vb {

enum class EmbreeCall { One, Packet8, Packet16, Stream };
// Which traced scene: RTC_SCENE_FLAG_ROBUST, or Embree's default flags (not robust); both of quality MEDIUM.
enum class TraceScene { Robust, Default };
const char* embreeCallName(EmbreeCall c, bool anyHit);

class EmbreeEngine {
public:
    struct Build {
        double ms = 0;      // best of the repetitions
        int64_t bytes = 0;  // memory the committed scene holds (memory monitor, net of the build's temporaries)
        int64_t peakBytes = 0;  // buildMesh: the most the monitor saw allocated during the build (temporaries included)
    };
    // What Embree's memory monitor reports: bytes allocated now, and the most since `peak` was last set.
    struct MemoryMonitor {
        std::atomic<int64_t> current{0}, peak{0};
        int64_t load() const { return current.load(); }
    };

    // rtcNewDevice("threads=N"); 0: Embree's default (all). Builds run on exactly N threads (a TBB arena of N).
    explicit EmbreeEngine(unsigned threads);
    ~EmbreeEngine();
    EmbreeEngine(const EmbreeEngine&) = delete;
    EmbreeEngine& operator=(const EmbreeEngine&) = delete;

    Build buildMesh(const Mesh& mesh, RTCBuildQuality quality, int reps);
    // A DYNAMIC scene of quality LOW whose geometry has quality REFIT: built once (bytes), then the vertices replaced by `moved`
    // (and back, alternately) and the scene recommitted; the time is rtcUpdateGeometryBuffer + commits.
    Build refitMesh(const Mesh& mesh, const std::vector<float>& moved, int reps);
    // A scene of instances of the mesh (its own scene committed beforehand, untimed).
    Build buildInstances(const Mesh& mesh, const std::vector<Transform>& xs, RTCBuildQuality quality, int reps);
    Build recommitInstances(const Mesh& mesh, const std::vector<Transform>& xs, const std::vector<Transform>& moved,
                            int reps);

    // SAH cost (sah.hpp) of rtcBuildBVH's tree over the triangles (Triangle4-like settings: 8-wide, SAH block 4,
    // leaves of 4 to 32; HIGH with spatial splits) or over boxes (instances: one per leaf).
    SahCost userBvhSah(const Mesh& mesh, RTCBuildQuality quality);
    SahCost userBvhSah(const std::vector<Box>& boxes, RTCBuildQuality quality);

    // The scenes traced: MEDIUM quality (Embree's default), robust and with the default flags.
    void makeTraceScene(const Scene& scene);
    double trace(EmbreeCall call, bool anyHit, bool coherent, const std::vector<VkasRay>& rays, std::vector<Hit>& hits,
                 unsigned threads, int reps, TraceScene which = TraceScene::Robust);

private:
    RTCScene meshScene(const Mesh& mesh, RTCBuildQuality sceneQuality, RTCBuildQuality geometryQuality,
                       RTCSceneFlags flags, const float* vertices);
    RTCScene instanceScene(RTCScene child, const std::vector<Transform>& xs, RTCBuildQuality quality,
                           RTCSceneFlags flags);

    // rtcCommitScene inside a TBB arena of the engine's thread count: Embree's "threads=N" sets a process-wide TBB
    // limit, so with a second device of more threads alive its builds would use those threads too.
    void commit(RTCScene s);

    unsigned threads_ = 0;
    RTCDevice device_ = nullptr;
    MemoryMonitor memory_;
    RTCScene traceChild_ = nullptr, traceScene_ = nullptr;      // robust
    RTCScene defaultChild_ = nullptr, defaultScene_ = nullptr;  // the default flags
};

}  // namespace vb
