// `vkas inspect FILE`: what a structure holds and how good its tree is. FILE is a mesh (built here into one bottom
// level, one geometry per placed mesh, with --preference) or a serialized structure (loaded, which is its integrity
// check). Prints the header and format version, counts, bytes by part, depth / leaf-size / children histograms, node
// fill, SAH cost and the sizes (query, compacted, serialized); --json the same as JSON; --boxes the boxes of one tree
// level as an OBJ.
#pragma once

#include <cstdint>
#include <string>

namespace vkas_tool {

struct InspectOptions {
    std::string file;
    std::string preference = "fast-trace";
    bool json = false;
    int64_t boxesLevel = -1;  // -1: no --boxes
    std::string boxesFile;
    std::string writeBlob;    // serialize the (built or loaded) structure to this file
    bool validation = true;
};

int runInspect(const InspectOptions& options);

}  // namespace vkas_tool
