// The lane search's engine compiled for AVX-512 (F, DQ, BW, VL) (maps/CMakeLists.txt).
#include "maps/cone_search_engine.h"

RS_DEFINE_CONE_SEARCH(Avx512)
