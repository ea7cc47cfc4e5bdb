# Heatmap and image-output sources of rs_metrics; include()d by metrics/CMakeLists.txt.
target_sources(rs_metrics PRIVATE ${CMAKE_CURRENT_LIST_DIR}/heatmap.cpp)
target_link_libraries(rs_metrics PRIVATE OpenImageIO::OpenImageIO)
