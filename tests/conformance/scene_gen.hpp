// Differential cases generated from a seed, one family per CTS-style group (docs/CONFORMANCE.md lists them).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "diff_case.hpp"

namespace diff {

// What both implementations can do: the vertex formats lavapipe accepts for acceleration-structure builds (vkas
// accepts all of them) and whether position fetch is available.
struct Capabilities {
    std::vector<VkFormat> vertexFormats;
    bool positionFetch = false;
};

struct Case {
    Scene scene;
    std::vector<Ray> rays;
    // Per ray: the exact number of surface crossings a watertight implementation reports (count mode), or -1.
    std::vector<int32_t> crossings;
};

// The groups, in the order the test runs them.
const std::vector<std::string>& caseGroups();
// One case of `group`; `variant` picks among the group's scene shapes (any value is valid).
Case makeCase(const std::string& group, uint32_t variant, uint64_t seed, const Capabilities& caps);

}  // namespace diff
