// Writes a mesh file as glTF 2 with assimp's exporter, so that the CLI tests read a glTF file that no package ships
// in this form: vkas_cli_export_gltf IN OUT.gltf (OUT.bin beside it).
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cstdio>

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: vkas_cli_export_gltf IN OUT.gltf\n");
        return 2;
    }
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(argv[1], aiProcess_Triangulate);
    if (!scene) {
        std::fprintf(stderr, "cannot read %s: %s\n", argv[1], importer.GetErrorString());
        return 1;
    }
    Assimp::Exporter exporter;
    if (exporter.Export(scene, "gltf2", argv[2]) != AI_SUCCESS) {
        std::fprintf(stderr, "cannot write %s: %s\n", argv[2], exporter.GetErrorString());
        return 1;
    }
    return 0;
}
