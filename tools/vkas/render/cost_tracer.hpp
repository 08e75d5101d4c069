// Traversal with counters, for `vkas heatmap`: a closest-hit traversal of a vkas top level and its triangle bottom
// levels that reads the documented bytes (docs/FORMAT.md) and counts what the ray costs: internal nodes visited
// (each one tests its 8 child boxes), instances entered, and triangles tested. The public API has no counters, so
// the tool walks the same tree the way vkas does (children nearest first, a child whose entry lies past the
// closest hit so far skipped); `vkas heatmap` checks its hits against vkasTraceRays pixel by pixel.
#pragma once

#include <cstdint>
#include <vector>

#include <vkas/vkas.h>

namespace vkas_tool {

struct TraceCounters {
    uint32_t nodes = 0;       // internal nodes visited, both levels
    uint32_t instances = 0;   // instance records tested
    uint32_t primitives = 0;  // triangles tested
};

struct CostHit {
    bool hit = false;
    float t = 0;
    int32_t instanceId = -1, primitiveIndex = -1;
};

class CostTracer {
public:
    // `bottomLevels[k]`: the block of the bottom level that instance k (its instanceId) refers to.
    CostTracer(const unsigned char* topLevel, std::vector<const unsigned char*> bottomLevels);
    CostHit trace(const VkasRay& ray, TraceCounters& counters) const;

private:
    const unsigned char* top_;
    std::vector<const unsigned char*> bottom_;
};

}  // namespace vkas_tool
