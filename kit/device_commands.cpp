// Commands::load: the command table resolved through vkasGetDeviceProcAddr.
#include "device_commands.hpp"

namespace vkas_kit {

MissingCommand::MissingCommand(const char* command)
    : std::runtime_error(std::string("vkasGetDeviceProcAddr(\"") + command + "\") returned NULL"), command_(command) {}

void Commands::load(VkDevice device) {
#define VKAS_KIT_LOAD(name) name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name));
#define VKAS_KIT_REQUIRE(name) \
    VKAS_KIT_LOAD(name)        \
    if (!name) throw MissingCommand(#name);
    VKAS_KIT_COMMANDS(VKAS_KIT_REQUIRE)
    VKAS_KIT_OPTIONAL_COMMANDS(VKAS_KIT_LOAD)
#undef VKAS_KIT_REQUIRE
#undef VKAS_KIT_LOAD
}

bool Commands::hasMicromaps() const {
#define VKAS_KIT_PRESENT(name) &&name != nullptr
    return true VKAS_KIT_OPTIONAL_COMMANDS(VKAS_KIT_PRESENT);
#undef VKAS_KIT_PRESENT
}

}  // namespace vkas_kit
