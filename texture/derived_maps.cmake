# Derived maps (issue #3): cone maps, mip pyramids, cache. Included from texture/CMakeLists.txt.
target_sources(rs_texture PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/cone_map.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cone_map_levels.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cone_map_generate.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cone_map_relaxed.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cone_map_adaptive.cpp
  ${CMAKE_CURRENT_LIST_DIR}/cone_map_io.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mip_pyramid.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mip_pyramid_io.cpp
  ${CMAKE_CURRENT_LIST_DIR}/map_cache.cpp)
# oneTBB inside the generators (results are bit-identical for any thread count), JSON stats.
target_link_libraries(rs_texture PUBLIC TBB::tbb PRIVATE nlohmann_json::nlohmann_json)
