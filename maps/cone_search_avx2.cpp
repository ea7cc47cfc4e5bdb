// The lane search's engine compiled for AVX2 (maps/CMakeLists.txt).
#include "maps/cone_search_engine.h"

RS_DEFINE_CONE_SEARCH(Avx2)
