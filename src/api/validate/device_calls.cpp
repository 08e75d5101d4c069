#include "api/validate/device_calls.hpp"

namespace vkas {

void reportLeakedObjects(Validator& v, size_t leaked) {
    v.fail("VUID-vkDestroyDevice-device-05137",
           "%zu objects (buffers, memory, acceleration structures or micromaps) created from device were not destroyed; "
           "vkas freed them.",
           leaked);
}

}  // namespace vkas
