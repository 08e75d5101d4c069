// What assimp's importer returned, checked before any post-processing step reads it. assimp's steps trust the
// importer: Triangulate, JoinIdenticalVertices and SortByPType index the vertex arrays with every face index and
// walk the node tree unchecked, and Triangulate asserts (abort) when a mesh's primitive types claim polygons it does
// not have. A truncated or damaged file gives exactly such data (a binary PLY cut short: faces of garbage indices),
// so the tool reads a file with no post-processing, checks it here, and only then runs the steps it needs.
#pragma once

#include <string>

namespace Assimp {
class Importer;
}

namespace vkas_tool {

// Polygons with more corners than this are split into a fan here: assimp's ear cutting takes time cubic in the
// corners in the worst case. Smaller polygons keep assimp's triangulation (the triangles the tool always made).
constexpr unsigned kMaxEarCutCorners = 256;

// Checks the importer's current scene and makes the preconditions of aiProcess_Triangulate,
// aiProcess_JoinIdenticalVertices and aiProcess_SortByPType true, or throws InputError naming `path` and the
// problem: a missing mesh, face array, vertex array or node; a face with no index or an index outside its mesh's
// vertices; a non-finite vertex in a mesh with triangles or polygons; bone weights or morph targets that do not fit their mesh;
// a node that places a mesh the file does not have; a node tree with a cycle, a shared node or more than 10,000
// levels. It sets each mesh's primitive types to those its faces have and fans polygons over kMaxEarCutCorners.
// A scene whose node tree is not a tree is given up (leaked): assimp could not free it.
void checkImportedScene(const std::string& path, Assimp::Importer& importer);

}  // namespace vkas_tool
