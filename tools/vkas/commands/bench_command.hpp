// `vkas bench FILE...`: the files' triangles (node transforms applied) as one mesh; build times for each
// preference (one thread and all threads), refit, compaction, and trace rates of camera, diffuse and shadow rays
// with one and all threads, as a table or --json. The measuring code is kit/measure (VkasEngine, the ray
// generators, EmbreeEngine): when the tool is built with Embree, every row has Embree's number beside vkas's.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vkas_tool {

struct BenchOptions {
    std::vector<std::string> files;
    uint32_t threads = 0;   // "all threads"; 0: all cores
    uint32_t rays = 65536;  // per ray kind
    int reps = 3;           // best of
    bool json = false;
    bool embree = true;     // compare with Embree when built with it
};

int runBench(const BenchOptions& options);

}  // namespace vkas_tool
