// Formats whose header announces its element counts (OFF, PLY): a file that announces far more vertices or faces
// than its bytes can hold is refused before assimp sizes its arrays from those counts (a few bytes claiming two
// billion vertices would make it allocate and read for minutes).
#pragma once

#include <cstdint>
#include <string>

namespace vkas_tool {

// Throws InputError when the header's counts cannot fit in `fileSize` bytes; does nothing for other formats.
void checkDeclaredCounts(const std::string& path, uint64_t fileSize);

}  // namespace vkas_tool
