# The measuring code of vkas_bench_embree as libraries, shared with `vkas bench` (tools/vkas), so that it is written
# and compiled once. Included by this folder's CMakeLists.txt and by tools/vkas/CMakeLists.txt, whichever comes first:
#   vkas_bench_common        the vkas side, the ray generators, the SAH cost, the mesh loader (vkas and assimp only)
#   vkas_bench_embree_engine the Embree 3 side (only when Embree 3 and TBB are found)
include_guard(GLOBAL)
# GLOBAL: the packages' imported targets are seen by both folders, whichever included this file.

find_package(assimp QUIET GLOBAL)
if(NOT assimp_FOUND)
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(ASSIMP IMPORTED_TARGET GLOBAL assimp)
  endif()
endif()
if(assimp_FOUND OR ASSIMP_FOUND)
  add_library(vkas_bench_common STATIC
    ${CMAKE_CURRENT_LIST_DIR}/scenes.cpp ${CMAKE_CURRENT_LIST_DIR}/rays.cpp ${CMAKE_CURRENT_LIST_DIR}/sah.cpp
    ${CMAKE_CURRENT_LIST_DIR}/vkas_side.cpp)
  target_include_directories(vkas_bench_common PUBLIC ${CMAKE_CURRENT_LIST_DIR})
  target_link_libraries(vkas_bench_common PUBLIC vkas::vkas_static Threads::Threads)
  if(TARGET assimp::assimp)
    target_link_libraries(vkas_bench_common PRIVATE assimp::assimp)
  else()
    target_link_libraries(vkas_bench_common PRIVATE PkgConfig::ASSIMP)
  endif()
endif()

find_package(embree 3 QUIET GLOBAL)
find_package(TBB QUIET GLOBAL)  # Embree's tasking system: the bench confines Embree's builds to N threads with a TBB arena
if(embree_FOUND AND TBB_FOUND)
  add_library(vkas_bench_embree_engine STATIC ${CMAKE_CURRENT_LIST_DIR}/embree_side.cpp)
  target_include_directories(vkas_bench_embree_engine PUBLIC ${CMAKE_CURRENT_LIST_DIR})
  target_link_libraries(vkas_bench_embree_engine PUBLIC vkas::vkas_static embree TBB::tbb Threads::Threads)
endif()
