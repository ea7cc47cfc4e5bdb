// The lane search's engine compiled for AVX2 (maps/CMakeLists.txt).
#define RS_CONE_SEARCH_LANES 8
#include "maps/cone_search_engine.h"

RS_DEFINE_CONE_SEARCH(Avx2)
