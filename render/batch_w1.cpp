// The fragment driver at 1 lane, compiled with the project's default flags.
#include "render/lane_driver.h"

RS_DEFINE_LANE_WIDTH(W1, 1)
