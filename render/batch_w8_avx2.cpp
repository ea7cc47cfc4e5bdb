// The fragment driver at 8 lanes, compiled for AVX2 with FMA (render/CMakeLists.txt).
#include "render/lane_driver.h"

RS_DEFINE_LANE_WIDTH(W8Avx2, 8)
