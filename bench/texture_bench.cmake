# Derived-map benchmarks (issue #3). Included from bench/CMakeLists.txt.
add_executable(texture_bench ${CMAKE_CURRENT_LIST_DIR}/texture_bench.cpp)
target_link_libraries(texture_bench PRIVATE rs_texture benchmark::benchmark rs_options)
