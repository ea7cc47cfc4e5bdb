// The fragment driver at 16 lanes, compiled for AVX-512 (F, VL, DQ, BW;
// render/CMakeLists.txt).
#include "render/lane_driver.h"

RS_DEFINE_LANE_WIDTH(W16Avx512, 16)
