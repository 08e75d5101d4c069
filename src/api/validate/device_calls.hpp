// The valid-usage rule vkasDestroyDevice (api/device.cpp) checks as vkDestroyDevice's last step: every object
// created from the device destroyed (vkDestroyDevice's parameters are checked by memory_calls.hpp).
#pragma once

#include <cstddef>

#include "api/validate/validator.hpp"

namespace vkas {

// Reports the `leaked` objects (not 0) that the device still held and vkas freed.
void reportLeakedObjects(Validator& v, size_t leaked);

}  // namespace vkas
