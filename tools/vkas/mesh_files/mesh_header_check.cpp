#include "mesh_header_check.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "input_error.hpp"

namespace vkas_tool {
namespace {

void refuse(const std::string& path, uint64_t vertices, uint64_t faces, uint64_t fileSize) {
    throw InputError(path, "truncated or malformed: its header announces " + std::to_string(vertices) +
                               " vertices and " + std::to_string(faces) + " faces, more than its " +
                               std::to_string(fileSize) + " bytes can hold");
}

// The least bytes a body of `count` items of `each` bytes takes, without wrapping: a header may announce counts
// near 2^64, whose product in 64 bits would wrap to a small number and pass the check (found by vkas_fuzz_mesh_file).
unsigned __int128 leastBytes(uint64_t count, uint64_t each) { return (unsigned __int128)count * each; }

}  // namespace

void checkDeclaredCounts(const std::string& path, uint64_t fileSize) {
    std::ifstream in(path, std::ios::binary);
    std::string first;
    if (!(in >> first)) return;
    // OFF: "[ST][C][N][4][n]OFF", then "vertices faces edges" (comments with '#' may come between).
    if (first.size() >= 3 && first.compare(first.size() - 3, 3, "OFF") == 0) {
        std::string line;
        std::getline(in, line);
        std::istringstream rest(line);
        uint64_t v = 0, f = 0;
        if (!(rest >> v >> f)) {
            while (std::getline(in, line)) {
                if (line.empty() || line[0] == '#') continue;
                std::istringstream counts(line);
                if (!(counts >> v >> f)) return;  // assimp reports it
                break;
            }
        }
        // A vertex takes at least "0 0 0\n" (6 bytes), a face "3 0 1 2\n" (8); binary OFF at least 12 and 16.
        if (leastBytes(v, 6) + leastBytes(f, 8) > fileSize) refuse(path, v, f, fileSize);
        if (first != "OFF") return;
        // ASCII OFF: assimp 5.2.5's reader crashes (SIGSEGV inside the importer) on a face line that holds fewer
        // indices than its count announces, so every face line is checked first: the count, then that many indices.
        uint64_t seen = 0;
        while (seen < v && std::getline(in, line))
            if (line.find_first_not_of(" \t\r") != std::string::npos && line[line.find_first_not_of(" \t\r")] != '#') ++seen;
        for (uint64_t face = 0; face < f && std::getline(in, line);) {
            const size_t at = line.find_first_not_of(" \t\r");
            if (at == std::string::npos || line[at] == '#') continue;
            std::istringstream words(line);
            uint64_t n = 0, index = 0;
            if (!(words >> n)) return;  // assimp reports it
            for (uint64_t k = 0; k < n; ++k)
                if (!(words >> index))
                    throw InputError(path, "truncated or malformed: OFF face " + std::to_string(face) + " announces " +
                                               std::to_string(n) + " vertex indices and holds " + std::to_string(k));
            ++face;
        }
        return;
    }
    // PLY: "element vertex N" / "element face M" lines up to "end_header"; at least 1 byte per property in binary,
    // 2 in ASCII, and a face at least a count and three indices.
    if (first == "ply") {
        std::string line, format;
        uint64_t v = 0, f = 0, vertexProps = 0;
        bool inVertex = false, ended = false;
        while (std::getline(in, line)) {
            if (line.rfind("end_header", 0) == 0) {
                ended = true;
                break;
            }
            std::istringstream words(line);
            std::string w, what;
            words >> w;
            if (w == "format") words >> format;
            else if (w == "element") {
                uint64_t n = 0;
                words >> what >> n;
                inVertex = what == "vertex";
                if (inVertex) v = n;
                else if (what == "face") f = n;
            } else if (w == "property" && inVertex) {
                ++vertexProps;
            }
        }
        // assimp's PLY reader loops forever on a header cut short (assimp 5.2.5): refused here.
        if (!ended) throw InputError(path, "not a mesh file assimp can read: its PLY header has no end_header line (truncated?)");
        const uint64_t perProp = format == "ascii" ? 2 : 1;
        if (leastBytes(v, std::max<uint64_t>(vertexProps, 3) * perProp) + leastBytes(f, 4 * perProp) > fileSize) refuse(path, v, f, fileSize);
    }
}

}  // namespace vkas_tool
