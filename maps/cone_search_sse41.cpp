// The lane search's engine compiled for baseline flags (SSE4.1) (maps/CMakeLists.txt).
#define RS_CONE_SEARCH_LANES 4
#include "maps/cone_search_engine.h"

RS_DEFINE_CONE_SEARCH(Sse41)
