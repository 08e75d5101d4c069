// A mesh file's scene as the importer process hands it to the tool (model_loader.cpp): plain arrays, no assimp type,
// and their byte form for the pipe between the two processes. The importer process runs assimp (model_import.cpp);
// the tool's own process only decodes these bytes, so an importer that writes out of bounds on a damaged file damages
// a process that ends with that one file, never the tool's heap.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vec_math.hpp"

namespace vkas_tool {

struct ImportedMesh {
    std::string name;
    uint32_t fileIndex = 0;         // the mesh's number in the imported scene (for messages)
    std::vector<Vec3> positions;
    std::vector<uint32_t> indices;  // three per triangle; points, lines and polygons are not kept
};

struct ImportedInstance {
    std::string node;      // the name of the node that places the mesh (for messages)
    uint32_t mesh = 0;     // into ImportedModel::meshes
    uint32_t material = 0; // into ImportedModel::albedos
    Affine transform;      // the node's world transform
};

struct ImportedModel {
    std::vector<Vec3> albedos;  // one per material of the file, at least one
    std::vector<ImportedMesh> meshes;
    std::vector<ImportedInstance> instances;
};

// What the importer process sends: the model, or the problem it found (the file's name left out).
struct ImportResult {
    enum class Kind : uint8_t { Model = 1, InputProblem = 2, OtherError = 3, OutOfMemory = 4 };
    Kind kind = Kind::Model;
    std::string message;  // InputProblem: what InputError(path, message) says; OtherError: the whole message
    ImportedModel model;
};

std::vector<uint8_t> encodeImportResult(const ImportResult& result);

// The bytes back, checked as they are read: every count against the bytes left, every index of an instance against
// its arrays, the trailer. Throws std::runtime_error when the bytes are not a whole, well-formed result (an importer
// process that died while writing). Values themselves (finite, indices inside a mesh) are the loader's to check.
ImportResult decodeImportResult(const std::vector<uint8_t>& bytes);

}  // namespace vkas_tool
