// The fragment driver at 4 lanes, compiled with the project's default flags.
#include "render/lane_driver.h"

RS_DEFINE_LANE_WIDTH(W4, 4)
