// The lane search's engine compiled for AVX-512 (F, DQ, BW, VL) (maps/CMakeLists.txt).
#define RS_CONE_SEARCH_LANES 16
#include "maps/cone_search_engine.h"

RS_DEFINE_CONE_SEARCH(Avx512)
