// `vkas info`: what the device reports (features, limits, vertex formats, commands) and the library version.
#pragma once

namespace vkas_tool {

struct InfoOptions {
    bool allFormats = false;  // also list the formats that cannot be used as vertex formats
};

int runInfo(const InfoOptions& options);

}  // namespace vkas_tool
