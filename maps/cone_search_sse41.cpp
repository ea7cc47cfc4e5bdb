// The lane search's engine compiled for baseline flags (SSE4.1) (maps/CMakeLists.txt).
#include "maps/cone_search_engine.h"

RS_DEFINE_CONE_SEARCH(Sse41)
