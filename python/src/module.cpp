// vkas._core's module definition (PYBIND11_MODULE: the Structure and Device classes, the exception translator to
// vkas.ValidationError) and the device: the debug messenger and DeviceImpl's creation and destruction.
#include <cstdio>
#include <thread>

#include "core.hpp"

namespace vkas_python {

namespace {

VKAPI_ATTR VkBool32 VKAPI_CALL messenger(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void*) {
    const char* id = data && data->pMessageIdName ? data->pMessageIdName : "";
    const char* text = data && data->pMessage ? data->pMessage : "";
    if (tlCapture) {
        try {
            tlCapture->push_back({id, text});
        } catch (...) {
        }
    } else {
        std::fprintf(stderr, "vkas: %s\n", text);
    }
    return VK_FALSE;
}

}  // namespace

DeviceImpl::DeviceImpl(bool validate, uint32_t threadCount) : validation(validate), requestedThreads(threadCount) {
    VkasDeviceCreateInfo ci{};
    ci.disableValidation = validate ? VK_FALSE : VK_TRUE;
    ci.pfnMessenger = &messenger;
    ci.workerThreadCount = threadCount;
    Capture capture;
    capture.check(vkasCreateDevice(&ci, &device), "vkasCreateDevice");
#define CORE_LOAD(name)                                                                                               \
    name = reinterpret_cast<PFN_##name>(vkasGetDeviceProcAddr(device, #name));                                        \
    if (!name) throw std::runtime_error("vkasGetDeviceProcAddr(" #name ") returned NULL");
    CORE_COMMANDS(CORE_LOAD)
#undef CORE_LOAD
    const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
    threads = threadCount == 0 ? hw : threadCount;
}
DeviceImpl::~DeviceImpl() {
    if (device) vkasDestroyDevice(device);
}

}  // namespace vkas_python

using namespace vkas_python;

PYBIND11_MODULE(_core, m) {
    m.doc() = "vkas._core: the C API binding behind the vkas package (use the vkas package itself)";
    m.attr("VERSION") = py::make_tuple(VKAS_VERSION_MAJOR, VKAS_VERSION_MINOR, VKAS_VERSION_PATCH);
    m.attr("RAY_QUERY_SIZE") = VKAS_RAY_QUERY_SIZE;

    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const ValidationFailure& e) {
            py::object cls = py::module_::import("vkas._errors").attr("ValidationError");
            py::list all;
            for (const Message& msg : e.messages) all.append(py::make_tuple(msg.vuid, msg.text));
            py::object exc = cls(e.messages.front().vuid, e.messages.front().text, all);
            PyErr_SetObject(cls.ptr(), exc.ptr());
        }
    });

    py::class_<Structure, StructurePtr>(m, "Structure")
        .def_property_readonly("handle", [](const Structure& s) { return uint64_t(reinterpret_cast<uintptr_t>(s.as)); })
        .def_property_readonly("address", &Structure::address)
        .def_property_readonly("size", [](const Structure& s) { return uint64_t(s.size); })
        .def_property_readonly("constructed", &Structure::constructed)
        .def_property_readonly("type", &Structure::type)
        .def_property_readonly("build_flags", &Structure::buildFlags)
        .def_property_readonly("used_size", &Structure::usedSize)
        .def("read", &Structure::read, py::arg("offset"), py::arg("count"))
        .def("query", [](const Structure& s, uint32_t type) {
            py::gil_scoped_release release;
            return s.query(VkQueryType(type));
        });

    py::class_<Device>(m, "Device")
        .def(py::init<bool, uint32_t>(), py::arg("validation"), py::arg("threads"))
        .def_property_readonly("validation", [](const Device& d) { return d.d->validation; })
        .def_property_readonly("threads", [](const Device& d) { return d.d->threads; })
        .def_property_readonly("requested_threads", [](const Device& d) { return d.d->requestedThreads; })
        .def("build_bottom", &Device::buildBottom)
        .def("update_bottom", &Device::updateBottom)
        .def("build_top", &Device::buildTop)
        .def("update_top", &Device::updateTop)
        .def("copy", &Device::copy)
        .def("serialize", &Device::serialize)
        .def("deserialize", &Device::deserialize)
        .def("check_ray_flags", &Device::checkRayFlags)
        .def("trace", &Device::trace)
        .def("trace_all", &Device::traceAll)
        .def("time_trace_rays", &Device::timeTraceRays)
        .def("pack_rays", &Device::packRaysForBench);
}
