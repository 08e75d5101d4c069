# Installation: the shared and static library, the public headers, a CMake package (find_package(vkas) gives
# vkas::vkas and vkas::vkas_static) and a pkg-config file (pkg-config vkas).
include(CMakePackageConfigHelpers)

set(VKAS_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/vkas" CACHE STRING
    "Where the CMake package files go, relative to the prefix")

install(TARGETS vkas vkas_static
  EXPORT vkasTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT development
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT development
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/vkas
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT development
  FILES_MATCHING PATTERN "*.h")

install(EXPORT vkasTargets
  NAMESPACE vkas::
  FILE vkasTargets.cmake
  DESTINATION ${VKAS_INSTALL_CMAKEDIR} COMPONENT development)
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/vkasConfig.cmake.in
  ${PROJECT_BINARY_DIR}/vkasConfig.cmake
  INSTALL_DESTINATION ${VKAS_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vkasConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)  # 0.x: a minor version may change the API
install(FILES ${PROJECT_BINARY_DIR}/vkasConfig.cmake ${PROJECT_BINARY_DIR}/vkasConfigVersion.cmake
  DESTINATION ${VKAS_INSTALL_CMAKEDIR} COMPONENT development)

# pkg-config: the prefix is found from the .pc file's own place (${pcfiledir}), so that the file stays right
# whatever `cmake --install --prefix` or DESTDIR says; absolute GNUInstallDirs directories stay absolute.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(VKAS_PC_PREFIX "${CMAKE_INSTALL_PREFIX}")
else()
  file(RELATIVE_PATH _vkas_pc_up "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
  string(REGEX REPLACE "/$" "" _vkas_pc_up "${_vkas_pc_up}")
  set(VKAS_PC_PREFIX "\${pcfiledir}/${_vkas_pc_up}")
endif()
foreach(dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_${dir}}")
    set(VKAS_PC_${dir} "${CMAKE_INSTALL_${dir}}")
  else()
    set(VKAS_PC_${dir} "\${prefix}/${CMAKE_INSTALL_${dir}}")
  endif()
endforeach()
configure_file(${CMAKE_CURRENT_LIST_DIR}/vkas.pc.in ${PROJECT_BINARY_DIR}/vkas.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/vkas.pc
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT development)
