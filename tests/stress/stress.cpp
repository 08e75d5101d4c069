// vkas_stress: bounded stress program of issue 20 (docs/API.md "Stress and soak").
//
// N threads issue random valid sequences of every command (create and destroy structures, build bottom levels of
// triangles or AABBs and top levels, deferred or not, update, copy (clone, compact), serialize and deserialize,
// compatibility checks, properties queries, ray queries and vkasTraceRays batches) on their own structures and on
// shared read-only structures built at the start, one set per device. Every hit is checked against the brute-force
// oracle; every structure a command makes or changes is digested (its serialized bytes, handle array zeroed), and
// after the concurrent phase each thread's sequence is replayed on one thread (deferred operations joined by that
// thread only) and must give the same digests. A thread's sequence depends only on the master seed and its index,
// never on timing, so `--seed X --threads N --ops K` replays it.
//
// --soak: rounds of --round-seconds each (fresh per-thread state every round, shared structures kept). Between rounds,
// with every worker joined, the program samples the heap bytes in use (glibc's mallinfo2, over every arena) and the
// resident set size (VmRSS). The heap bytes in use are the leak test: they must come back to the warm-up's level
// after every round. RSS, which also holds what the allocator keeps and which arenas fragment, is checked for a
// trend only: the median of the last third of the rounds against the median of the first third after warm-up.
#include <malloc.h>
#include <xxhash.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "host_kit.hpp"
#include "meshes.hpp"

namespace {

using Clock = std::chrono::steady_clock;

// ---- Commands ---------------------------------------------------------------------------------------------------
enum Command : uint32_t {
    kCreateDestroy,
    kBuildTriangles,
    kBuildAabbs,
    kBuildTlas,
    kUpdateBlas,
    kUpdateTlas,
    kClone,
    kCompact,
    kSerializeDeserialize,
    kProperties,
    kDestroy,
    kRayQueries,
    kBatchTrace,
    kSharedReads,
    kCommandCount
};
const char* const kCommandNames[kCommandCount] = {
    "create+destroy", "build BLAS triangles", "build BLAS AABBs", "build TLAS",     "update BLAS",
    "update TLAS",    "copy clone",           "copy compact",     "serialize+deserialize (+compatibility)",
    "properties",     "destroy",              "ray queries",      "batch traces",   "shared structures: serialize, trace"};
// Relative frequencies.
const uint32_t kWeights[kCommandCount] = {3, 10, 5, 8, 6, 4, 4, 4, 5, 4, 6, 8, 8, 4};

struct Options {
    double seconds = 60;
    uint32_t threads = std::max(1u, std::thread::hardware_concurrency());
    uint64_t seed = 0;
    bool seedGiven = false;
    uint64_t ops = 0;  // per thread; 0: no cap
    uint32_t devices = 1;
    uint32_t maxTriangles = 2000;
    bool soak = false;
    double roundSeconds = 10;
    bool replay = true;
    uint32_t replayJobs = std::max(1u, std::thread::hardware_concurrency());
};

uint64_t splitmix(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

uint64_t digest(const std::vector<uint8_t>& bytes) { return XXH3_64bits(bytes.data(), bytes.size()); }

// Per command: how many ran, over all threads (and rounds).
std::array<std::atomic<uint64_t>, kCommandCount> gCounts{};
std::atomic<uint64_t> gRays{0}, gHits{0}, gDeferred{0};
std::atomic<bool> gStop{false};

// What the devices share: read-only structures built at the start, and their blobs.
struct Shared {
    std::unique_ptr<hk::Device> device;
    std::unique_ptr<hk::Geometry> triangles, boxes;
    std::unique_ptr<hk::Structure> blas, aabbBlas, tlas;
    std::vector<uint8_t> blasBlob, tlasBlob;  // canonical
};

std::unique_ptr<Shared> makeShared(uint64_t seed, uint32_t maxTriangles) {
    auto s = std::make_unique<Shared>();
    vt::Rng rng(seed);
    s->device = std::make_unique<hk::Device>(2);
    s->triangles = hk::triangles(vt::triangleSoup(int(std::max(16u, maxTriangles)), rng, 0.3f));
    s->boxes = hk::aabbs(hk::randomBoxes(rng, std::max(8u, maxTriangles / 4), 1.0f, 0.2f));
    s->blas = hk::buildBlas(*s->device, {s->triangles.get()}, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR);
    s->aabbBlas = hk::buildBlas(*s->device, {s->boxes.get()}, 0);
    std::vector<hk::InstanceDesc> instances(12);
    for (uint32_t i = 0; i < instances.size(); ++i) {
        instances[i].transform = vt::randomTransform(rng, 0.5f, 1.5f, rng.coin(0.2), 5.0f);
        instances[i].customIndex = i;
        instances[i].blas = i % 3 ? s->blas.get() : s->aabbBlas.get();
    }
    s->tlas = hk::buildTlas(*s->device, instances, 0);
    s->blasBlob = hk::canonicalBlob(hk::serialize(*s->device, *s->blas));
    s->tlasBlob = hk::canonicalBlob(hk::serialize(*s->device, *s->tlas));
    return s;
}

// ---- One thread's sequence --------------------------------------------------------------------------------------
struct Object {
    uint64_t id = 0;
    std::unique_ptr<hk::Structure> s;
    std::vector<std::unique_ptr<hk::Geometry>> geometries;  // BLAS: its current data (for updates)
    std::vector<hk::InstanceDesc> instances;                // TLAS
    std::vector<uint64_t> dependencies;                     // TLAS: ids of the own BLAS it references
    bool updatable = false;
    bool tlas() const { return s->type == VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR; }
};

struct Record {
    uint64_t op;  // index of the command in the thread's sequence
    uint32_t command;
    uint64_t digest;
};

class Worker {
  public:
    Worker(uint64_t seed, Shared& shared, const Options& opt, bool replay)
        : rng_(seed), shared_(shared), d_(*shared.device), opt_(opt), replay_(replay) {}

    // Runs commands until the deadline, the cap or a stop; returns the number run. Throws hk::Failure on a difference
    // (with the command index in `failedAt`).
    uint64_t run(Clock::time_point deadline, uint64_t cap) {
        uint64_t n = 0;
        while ((cap == 0 || n < cap) && Clock::now() < deadline && !gStop.load(std::memory_order_relaxed)) {
            current_ = n;
            step();
            ++n;
        }
        objects_.clear();
        return n;
    }
    const std::vector<Record>& records() const { return records_; }
    uint64_t current() const { return current_; }
    uint32_t currentCommand() const { return command_; }

  private:
    uint32_t joinCount() {
        const uint32_t j = rng_.coin(0.5) ? 0 : 1 + rng_.below(3);
        if (j && !replay_) ++gDeferred;
        return replay_ ? std::min(j, 1u) : j;  // the replay joins on its own thread only
    }
    VkBuildAccelerationStructureFlagsKHR randomFlags(bool update, bool compaction) {
        static const VkBuildAccelerationStructureFlagsKHR preference[] = {
            0, VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_TRACE_BIT_KHR,
            VK_BUILD_ACCELERATION_STRUCTURE_PREFER_FAST_BUILD_BIT_KHR,
            VK_BUILD_ACCELERATION_STRUCTURE_LOW_MEMORY_BIT_KHR};
        VkBuildAccelerationStructureFlagsKHR f = preference[rng_.below(4)];
        if (update) f |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_UPDATE_BIT_KHR;
        if (compaction) f |= VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR;
        return f;
    }
    void record(uint64_t value) { records_.push_back({current_, command_, value}); }
    void recordStructure(const hk::Structure& s) { record(digest(hk::canonicalBlob(hk::serialize(d_, s)))); }

    std::vector<size_t> indicesWhere(bool tlas, bool needUpdatable = false, VkBuildAccelerationStructureFlagsKHR flag = 0) {
        std::vector<size_t> out;
        for (size_t i = 0; i < objects_.size(); ++i)
            if (objects_[i].tlas() == tlas && (!needUpdatable || objects_[i].updatable) &&
                (!flag || (objects_[i].s->flags & flag)))
                out.push_back(i);
        return out;
    }
    size_t pick(const std::vector<size_t>& v) { return v[rng_.below(uint32_t(v.size()))]; }

    Object& add(Object o) {
        o.id = nextId_++;
        objects_.push_back(std::move(o));
        recordStructure(*objects_.back().s);
        return objects_.back();
    }
    // Destroys object i and every top level that references it.
    void destroy(size_t i) {
        const uint64_t id = objects_[i].id;
        objects_.erase(objects_.begin() + ptrdiff_t(i));
        objects_.erase(std::remove_if(objects_.begin(), objects_.end(),
                                      [&](const Object& o) {
                                          return std::find(o.dependencies.begin(), o.dependencies.end(), id) !=
                                                 o.dependencies.end();
                                      }),
                       objects_.end());
    }

    uint32_t choose() {
        uint32_t total = 0;
        for (uint32_t w : kWeights) total += w;
        uint32_t r = rng_.below(total), c = 0;
        while (r >= kWeights[c]) r -= kWeights[c++];
        const bool haveBlas = !indicesWhere(false).empty(), haveTlas = !indicesWhere(true).empty();
        if (objects_.size() >= 16 && (c == kBuildTriangles || c == kBuildAabbs || c == kBuildTlas)) c = kDestroy;
        if (!haveBlas && c != kCreateDestroy && c != kSharedReads && c != kBuildAabbs) c = kBuildTriangles;
        if ((c == kUpdateTlas || c == kRayQueries || c == kBatchTrace) && !haveTlas) c = kBuildTlas;
        if (c == kUpdateBlas && indicesWhere(false, true).empty()) c = kBuildTriangles;
        if (c == kUpdateTlas && indicesWhere(true, true).empty()) c = kBuildTlas;
        if (c == kCompact && indicesWhere(false, false, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR).empty() &&
            indicesWhere(true, false, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR).empty())
            c = kClone;
        return c;
    }

    std::unique_ptr<hk::Geometry> randomGeometry(bool boxes) {
        const uint32_t count = 16 + rng_.below(std::max(1u, opt_.maxTriangles - 15));
        const VkGeometryFlagsKHR flags = rng_.coin(0.7) ? VK_GEOMETRY_OPAQUE_BIT_KHR : 0;
        if (boxes) return hk::aabbs(hk::randomBoxes(rng_, std::max(1u, count / 4), 1.0f, 0.2f), flags);
        if (rng_.coin(0.5)) return hk::triangles(vt::triangleSoup(int(count), rng_, 0.3f), flags);
        const int n = std::max(2, int(std::sqrt(count / 2.0)));
        return hk::triangles(vt::terrain(n, rng_), flags);
    }
    std::unique_ptr<hk::Geometry> copyOf(const hk::Geometry& g) {
        auto c = std::make_unique<hk::Geometry>();
        c->positions = g.positions, c->indices = g.indices, c->boxes = g.boxes, c->flags = g.flags;
        c->refresh();
        return c;
    }
    // A copy of object o's description (geometry, instances, dependencies) for a structure made from it.
    Object derived(const Object& o, std::unique_ptr<hk::Structure> s, bool updatable) {
        Object n;
        n.s = std::move(s);
        for (const auto& g : o.geometries) n.geometries.push_back(copyOf(*g));
        n.instances = o.instances;
        n.dependencies = o.dependencies;
        n.updatable = updatable;
        return n;
    }

    // Rays through a top level, checked (not in the replay, where only their random draws are made).
    void trace(const hk::Structure& tlas, bool batch) {
        const size_t count = 8 + rng_.below(24);
        const uint32_t flags = rng_.coin(0.3) ? VKAS_RAY_FLAG_TERMINATE_ON_FIRST_HIT : 0;
        const auto rays = hk::randomRays(*tlas.scene, rng_, count);
        if (replay_) return;
        const auto expected = hk::expectedResults(*tlas.scene, rays, flags);
        const bool closest = flags == 0;
        std::vector<vt::Hit> hits = batch ? hk::batchTrace(d_, tlas.handle, rays,
                                                           closest ? VKAS_TRACE_MODE_CLOSEST_HIT : VKAS_TRACE_MODE_ANY_HIT, 0)
                                          : hk::rayQueries(tlas.handle, rays, flags);
        gHits += hk::checkHits(expected, rays, hits, closest, batch ? "vkasTraceRays" : "ray queries");
        gRays += count;
    }

    void step() {
        command_ = choose();
        if (!replay_) ++gCounts[command_];
        switch (command_) {
        case kCreateDestroy: {
            const bool tlas = rng_.coin(0.5);
            const VkDeviceSize size = 256 * (1 + rng_.below(64));
            auto s = hk::createStructure(d_, tlas ? VK_ACCELERATION_STRUCTURE_TYPE_TOP_LEVEL_KHR
                                                  : VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR, size);
            record(size);
            break;
        }
        case kBuildTriangles:
        case kBuildAabbs: {
            Object o;
            o.geometries.push_back(randomGeometry(command_ == kBuildAabbs));
            if (command_ == kBuildTriangles && rng_.coin(0.3)) o.geometries.push_back(randomGeometry(false));
            const bool update = rng_.coin(0.5), compaction = rng_.coin(0.5);
            std::vector<const hk::Geometry*> g;
            for (const auto& x : o.geometries) g.push_back(x.get());
            const auto flags = randomFlags(update, compaction);
            o.s = hk::buildBlas(d_, g, flags, joinCount());
            o.updatable = update;
            add(std::move(o));
            break;
        }
        case kBuildTlas: {
            const auto blases = indicesWhere(false);
            Object o;
            const uint32_t n = 1 + rng_.below(8);
            for (uint32_t i = 0; i < n; ++i) {
                hk::InstanceDesc inst;
                inst.transform = vt::randomTransform(rng_, 0.5f, 1.5f, rng_.coin(0.2), 4.0f);
                inst.customIndex = rng_.u32() & 0xFFFFFF;
                inst.sbtOffset = rng_.below(16);
                const uint32_t which = rng_.below(4);
                if (which == 0 || blases.empty()) {
                    inst.blas = rng_.coin(0.7) ? shared_.blas.get() : shared_.aabbBlas.get();
                } else {
                    const Object& b = objects_[pick(blases)];
                    inst.blas = b.s.get();
                    if (std::find(o.dependencies.begin(), o.dependencies.end(), b.id) == o.dependencies.end())
                        o.dependencies.push_back(b.id);
                }
                o.instances.push_back(inst);
            }
            const bool update = rng_.coin(0.5), compaction = rng_.coin(0.3);
            o.s = hk::buildTlas(d_, o.instances, randomFlags(update, compaction), joinCount());
            o.updatable = update;
            add(std::move(o));
            break;
        }
        case kUpdateBlas: {
            const size_t i = pick(indicesWhere(false, true));
            Object& o = objects_[i];
            for (auto& g : o.geometries) hk::jitter(*g, rng_, 0.02f);
            std::vector<const hk::Geometry*> g;
            for (const auto& x : o.geometries) g.push_back(x.get());
            const bool inPlace = rng_.coin(0.5);
            auto s = hk::updateBlas(d_, *o.s, g, inPlace, joinCount());
            if (inPlace) {
                recordStructure(*o.s);
                // Top levels over it would see a changed bottom level: they go (as an application rebuilds them).
                const uint64_t id = o.id;
                objects_.erase(std::remove_if(objects_.begin(), objects_.end(),
                                              [&](const Object& x) {
                                                  return std::find(x.dependencies.begin(), x.dependencies.end(), id) !=
                                                         x.dependencies.end();
                                              }),
                               objects_.end());
            } else {
                add(derived(o, std::move(s), true));
            }
            break;
        }
        case kUpdateTlas: {
            const size_t i = pick(indicesWhere(true, true));
            Object& o = objects_[i];
            for (auto& inst : o.instances) inst.transform = vt::randomTransform(rng_, 0.5f, 1.5f, rng_.coin(0.2), 4.0f);
            const bool inPlace = rng_.coin(0.5);
            auto s = hk::updateTlas(d_, *o.s, o.instances, inPlace, joinCount());
            if (inPlace)
                recordStructure(*o.s);
            else
                add(derived(o, std::move(s), true));
            break;
        }
        case kClone: {
            const size_t i = rng_.below(uint32_t(objects_.size()));
            auto s = hk::cloneStructure(d_, *objects_[i].s, joinCount());
            if (hk::structureBytes(*s) != hk::structureBytes(*objects_[i].s)) hk::fail("a clone's bytes differ from its source's");
            add(derived(objects_[i], std::move(s), objects_[i].updatable));
            break;
        }
        case kCompact: {
            std::vector<size_t> v = indicesWhere(false, false, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR);
            for (size_t x : indicesWhere(true, false, VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR)) v.push_back(x);
            std::sort(v.begin(), v.end());
            const size_t i = pick(v);
            auto s = hk::compactStructure(d_, *objects_[i].s, joinCount());
            add(derived(objects_[i], std::move(s), false));
            break;
        }
        case kSerializeDeserialize: {
            const size_t i = rng_.below(uint32_t(objects_.size()));
            const auto blob = hk::serialize(d_, *objects_[i].s, joinCount());
            if (hk::compatibility(d_, blob) != VK_ACCELERATION_STRUCTURE_COMPATIBILITY_COMPATIBLE_KHR)
                hk::fail("vkGetDeviceAccelerationStructureCompatibilityKHR: a blob of this device is not compatible");
            auto s = hk::deserialize(d_, blob, objects_[i].s->type, joinCount());
            s->blas = objects_[i].s->blas;
            s->scene = objects_[i].s->scene;
            s->flags = objects_[i].s->flags;
            if (hk::canonicalBlob(hk::serialize(d_, *s)) != hk::canonicalBlob(blob))
                hk::fail("serialize(deserialize(blob)) differs from blob");
            add(derived(objects_[i], std::move(s), false));
            break;
        }
        case kProperties: {
            const size_t i = rng_.below(uint32_t(objects_.size()));
            const auto& s = *objects_[i].s;
            const VkDeviceSize serialized =
                hk::queryProperty(d_, s, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_SERIALIZATION_SIZE_KHR);
            if (serialized < 56) hk::fail("serialization size below the header's");
            uint64_t value = serialized;
            if (s.flags & VK_BUILD_ACCELERATION_STRUCTURE_ALLOW_COMPACTION_BIT_KHR) {
                const VkDeviceSize compacted = hk::queryProperty(d_, s, VK_QUERY_TYPE_ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR);
                if (compacted == 0 || compacted > s.size) hk::fail("compacted size out of range");
                value = value * 31 + compacted;
            }
            record(value);
            break;
        }
        case kDestroy: {
            if (objects_.empty()) break;
            destroy(rng_.below(uint32_t(objects_.size())));
            record(objects_.size());
            break;
        }
        case kRayQueries:
        case kBatchTrace: {
            const auto tl = indicesWhere(true);
            trace(*objects_[pick(tl)].s, command_ == kBatchTrace);
            break;
        }
        case kSharedReads: {
            const uint32_t what = rng_.below(3);
            if (what == 0) {
                if (!replay_ && hk::canonicalBlob(hk::serialize(d_, *shared_.blas)) != shared_.blasBlob)
                    hk::fail("the shared bottom level's serialized bytes changed");
            } else if (what == 1) {
                const uint32_t join = joinCount();
                if (!replay_ && hk::canonicalBlob(hk::serialize(d_, *shared_.tlas, join)) != shared_.tlasBlob)
                    hk::fail("the shared top level's serialized bytes changed");
            } else {
                trace(*shared_.tlas, rng_.coin(0.5));
            }
            break;
        }
        }
    }

    vt::Rng rng_;
    Shared& shared_;
    hk::Device& d_;
    const Options& opt_;
    bool replay_;
    std::vector<Object> objects_;
    std::vector<Record> records_;
    uint64_t nextId_ = 0, current_ = 0;
    uint32_t command_ = 0;
};

// ---- Driver -----------------------------------------------------------------------------------------------------
[[noreturn]] void usage(const char* why) {
    std::fprintf(stderr,
                 "vkas_stress: %s\n"
                 "usage: vkas_stress [--seconds S] [--threads N] [--seed X] [--ops N] [--devices D] [--max-triangles T]\n"
                 "                   [--no-replay] [--replay-jobs J] [--soak [--round-seconds R]]\n",
                 why);
    std::exit(2);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) usage(("missing value after " + a).c_str());
            return argv[++i];
        };
        if (a == "--seconds") o.seconds = std::atof(value());
        else if (a == "--threads") o.threads = uint32_t(std::max(1, std::atoi(value())));
        else if (a == "--seed") o.seed = std::strtoull(value(), nullptr, 0), o.seedGiven = true;
        else if (a == "--ops") o.ops = std::strtoull(value(), nullptr, 0);
        else if (a == "--devices") o.devices = uint32_t(std::max(1, std::atoi(value())));
        else if (a == "--max-triangles") o.maxTriangles = uint32_t(std::max(16, std::atoi(value())));
        else if (a == "--soak") o.soak = true;
        else if (a == "--round-seconds") o.roundSeconds = std::max(0.5, std::atof(value()));
        else if (a == "--no-replay") o.replay = false;
        else if (a == "--replay-jobs") o.replayJobs = uint32_t(std::max(1, std::atoi(value())));
        else if (a == "--help" || a == "-h") usage("help");
        else usage(("unknown option " + a).c_str());
    }
    if (!o.seedGiven) {
        std::random_device rd;
        o.seed = (uint64_t(rd()) << 32) ^ rd();
    }
    return o;
}

std::string replayLine(const Options& o, uint64_t ops) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "vkas_stress --seed %" PRIu64 " --threads %u --devices %u --max-triangles %u --ops %" PRIu64
                  " --seconds 100000", o.seed, o.threads, o.devices, o.maxTriangles, ops);
    return buf;
}

uint64_t threadSeed(uint64_t master, uint32_t round, uint32_t t) {
    return splitmix(master ^ splitmix((uint64_t(round) << 32) + t + 1));
}

struct Phase {
    std::vector<uint64_t> ops;
    std::vector<std::vector<Record>> records;
    bool failed = false;
};

// The heap bytes the program holds: in use in every malloc arena plus the blocks mapped on their own.
uint64_t heapBytesInUse() {
    const struct mallinfo2 m = mallinfo2();
    return uint64_t(m.uordblks) + uint64_t(m.hblkhd);
}

// Runs the threads until the deadline. On a failure prints it and sets gStop.
Phase runPhase(const Options& o, std::vector<std::unique_ptr<Shared>>& shared, uint32_t round, Clock::time_point deadline) {
    Phase p;
    p.ops.assign(o.threads, 0);
    p.records.resize(o.threads);
    std::mutex printMutex;
    std::vector<std::thread> pool;
    for (uint32_t t = 0; t < o.threads; ++t)
        pool.emplace_back([&, t] {
            Worker w(threadSeed(o.seed, round, t), *shared[t % o.devices], o, false);
            try {
                p.ops[t] = w.run(deadline, o.ops);
                p.records[t] = w.records();
            } catch (const std::exception& e) {
                std::lock_guard<std::mutex> lock(printMutex);
                if (!gStop.exchange(true)) {
                    std::printf("vkas_stress: FAILED: thread %u, command %" PRIu64 " (%s), round %u: %s\n"
                                "vkas_stress: seed %" PRIu64 "; replay with: %s\n",
                                t, w.current(), kCommandNames[w.currentCommand()], round, e.what(), o.seed,
                                replayLine(o, w.current() + 1).c_str());
                    std::fflush(stdout);
                }
                p.failed = true;
            }
        });
    for (auto& th : pool) th.join();
    return p;
}

// Replays each thread's sequence on one thread until the deadline: the records of the commands replayed must be the
// concurrent run's. Counts the commands replayed in `replayed`.
bool replayPhase(const Options& o, std::vector<std::unique_ptr<Shared>>& shared, const Phase& p, Clock::time_point deadline,
                 std::atomic<uint64_t>& replayed) {
    std::atomic<uint32_t> next{0};
    std::atomic<bool> ok{true};
    std::mutex printMutex;
    std::vector<std::thread> pool;
    for (uint32_t j = 0; j < std::min(o.replayJobs, o.threads); ++j)
        pool.emplace_back([&] {
            for (uint32_t t; (t = next++) < o.threads && ok;) {
                Worker w(threadSeed(o.seed, 0, t), *shared[t % o.devices], o, true);
                std::string problem;
                uint64_t at = 0;
                try {
                    const uint64_t n = w.run(deadline, p.ops[t]);
                    replayed += n;
                    std::vector<Record> a;
                    for (const Record& r : p.records[t])
                        if (r.op < n) a.push_back(r);
                    const auto& b = w.records();
                    for (size_t k = 0; k < std::max(a.size(), b.size()) && problem.empty(); ++k)
                        if (k >= a.size() || k >= b.size() || a[k].command != b[k].command || a[k].digest != b[k].digest) {
                            char buf[256];
                            std::snprintf(buf, sizeof buf, "result %zu (%s) differs from the single-threaded replay's (%s)", k,
                                          k < a.size() ? kCommandNames[a[k].command] : "none",
                                          k < b.size() ? kCommandNames[b[k].command] : "none");
                            problem = buf;
                        }
                    at = p.ops[t];
                } catch (const std::exception& e) {
                    problem = std::string("the replay failed: ") + e.what();
                    at = w.current() + 1;
                }
                if (!problem.empty()) {
                    std::lock_guard<std::mutex> lock(printMutex);
                    ok = false;
                    std::printf("vkas_stress: FAILED: thread %u: %s\nvkas_stress: seed %" PRIu64 "; replay with: %s\n", t,
                                problem.c_str(), o.seed, replayLine(o, std::max<uint64_t>(at, p.ops[t])).c_str());
                    std::fflush(stdout);
                }
            }
        });
    for (auto& th : pool) th.join();
    return ok;
}

void printCounts() {
    std::printf("vkas_stress: commands run:\n");
    uint64_t total = 0;
    for (uint32_t c = 0; c < kCommandCount; ++c) {
        std::printf("  %-42s %10" PRIu64 "\n", kCommandNames[c], gCounts[c].load());
        total += gCounts[c];
    }
    std::printf("  %-42s %10" PRIu64 "\n  rays checked against the oracle %20" PRIu64 " (%" PRIu64 " hits)\n"
                "  commands through a deferred operation %14" PRIu64 "\n",
                "total", total, gRays.load(), gHits.load(), gDeferred.load());
}

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);
    const auto start = Clock::now();
    std::printf("vkas_stress: seed %" PRIu64 ", %u threads, %u device(s), %.1f s, max %u triangles%s%s\n", o.seed,
                o.threads, o.devices, o.seconds, o.maxTriangles, o.soak ? ", soak" : "",
                o.soak || !o.replay ? ", no replay" : ", with replay");
    std::fflush(stdout);
    std::vector<std::unique_ptr<Shared>> shared;
    try {
        for (uint32_t i = 0; i < o.devices; ++i) shared.push_back(makeShared(splitmix(o.seed + i), o.maxTriangles));
    } catch (const std::exception& e) {
        std::printf("vkas_stress: FAILED: shared structures: %s (seed %" PRIu64 ")\n", e.what(), o.seed);
        return 1;
    }
    auto seconds = [](double s) { return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s)); };
    int status = 0;
    if (o.soak) {
        // Fixed, so that glibc's threshold does not climb with the freed sizes: large blocks (structure memory) are
        // mapped and unmapped, and RSS follows what is live rather than what an arena once held.
        mallopt(M_MMAP_THRESHOLD, 1 << 20);
        const uint32_t rounds = std::max(1u, uint32_t(o.seconds / o.roundSeconds));
        const uint32_t warmup = std::min(3u, rounds - 1);
        uint64_t baselineHeap = 0;
        std::vector<double> rssAfter;  // MiB, rounds after warm-up
        for (uint32_t r = 0; r < rounds && !status; ++r) {
            const auto roundStart = Clock::now();
            Phase p = runPhase(o, shared, r, std::min(roundStart + seconds(o.roundSeconds), start + seconds(o.seconds)));
            if (p.failed) status = 1;
            uint64_t ops = 0;
            for (uint64_t n : p.ops) ops += n;
            p = Phase{};  // the round's records go too: what stays is the shared structures and the devices
            malloc_trim(0);
            const uint64_t heap = heapBytesInUse(), rss = hk::residentBytes();
            if (r < warmup || baselineHeap == 0) baselineHeap = std::max(baselineHeap, heap);
            else rssAfter.push_back(rss / 1048576.0);
            // The tolerance: what a few caches of the C++ runtime and the allocator's own bookkeeping may add.
            const uint64_t heapLimit = baselineHeap + std::max<uint64_t>(1ull << 20, baselineHeap / 100);
            std::printf("vkas_stress: round %u/%u: %" PRIu64 " commands, %.1f s, heap in use %.2f MiB, VmRSS %.1f MiB%s\n",
                        r + 1, rounds, ops, std::chrono::duration<double>(Clock::now() - roundStart).count(),
                        heap / 1048576.0, rss / 1048576.0, r < warmup ? " (warm-up)" : "");
            std::fflush(stdout);
            if (r >= warmup && heap > heapLimit) {
                std::printf("vkas_stress: FAILED: heap in use grew to %.2f MiB between rounds, past %.2f MiB (warm-up "
                            "peak %.2f MiB + tolerance): a leak; seed %" PRIu64 "\n",
                            heap / 1048576.0, heapLimit / 1048576.0, baselineHeap / 1048576.0, o.seed);
                status = 1;
            }
        }
        if (!status && rssAfter.size() >= 6) {
            auto median = [](std::vector<double> v) {
                std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
                return v[v.size() / 2];
            };
            const size_t third = rssAfter.size() / 3;
            const double first = median({rssAfter.begin(), rssAfter.begin() + third});
            const double last = median({rssAfter.end() - third, rssAfter.end()});
            const bool flat = last <= first * 1.25 + 32;
            std::printf("vkas_stress: VmRSS between rounds, median of the first third %.1f MiB, of the last third %.1f "
                        "MiB: %s\n", first, last, flat ? "flat" : "GROWING");
            if (!flat) status = 1;
        }
    } else {
        // With the replay, the concurrent phase has 60% of the time and the replay the rest: it redoes the commands
        // but not the traces (most of the work), on all cores, as far as it gets (all of it, unless under a sanitizer).
        const double concurrent = o.replay ? o.seconds * 0.6 : o.seconds;
        Phase p = runPhase(o, shared, 0, start + seconds(concurrent));
        if (p.failed) status = 1;
        uint64_t ops = 0;
        for (uint64_t n : p.ops) ops += n;
        std::printf("vkas_stress: concurrent phase: %" PRIu64 " commands in %.1f s\n", ops,
                    std::chrono::duration<double>(Clock::now() - start).count());
        if (!status && o.replay) {
            const auto replayStart = Clock::now();
            std::atomic<uint64_t> replayed{0};
            if (!replayPhase(o, shared, p, start + seconds(o.seconds), replayed)) status = 1;
            std::printf("vkas_stress: single-threaded replay of each thread's sequence: %s, %" PRIu64 " of %" PRIu64
                        " commands replayed in %.1f s\n", status ? "DIFFERENT" : "identical", replayed.load(), ops,
                        std::chrono::duration<double>(Clock::now() - replayStart).count());
        }
    }
    for (auto& s : shared) {
        for (const auto& e : s->device->takeErrors()) {
            std::printf("vkas_stress: FAILED: validation error: %s\n", e.c_str());
            status = 1;
        }
    }
    printCounts();
    std::printf("vkas_stress: %s in %.1f s (seed %" PRIu64 ")\n", status ? "FAILED" : "passed",
                std::chrono::duration<double>(Clock::now() - start).count(), o.seed);
    return status;
}
