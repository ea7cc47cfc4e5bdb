// Lane-cost probe (included before the kernel when the runner measures lanes): counts every
// executed trip of the kernel loop once per SIMD group, by the group's first active lane
// (GL_ARB_shader_ballot). Inactive lanes cannot execute code, but a trip only runs while at
// least one lane is active, so "first active lane" sees every trip the group executes.

layout(std430, binding = 0) buffer LaneCost {
    uint gGroupRuns;        // shader runs of a lane group (counted by its first lane)
    uint gShapeViolations;  // lanes whose group spans more than one (block, triangle)
    uint gSubgroupSize;     // gl_SubGroupSizeARB
    uint gPad;
    uint gGroupTrips[];     // executed loop trips per (4x2 block, triangle)
};
uniform int uBlocksX;      // blocks per row: ceil(width / 4)
uniform int uNumTriangles;

int gGroupKey;

bool IsFirstActiveLane() {
    return readFirstInvocationARB(gl_SubGroupInvocationARB) == gl_SubGroupInvocationARB;
}

#define RS_ON_TRIP() \
    if (IsFirstActiveLane()) atomicAdd(gGroupTrips[gGroupKey], 1u)

// Called once at the start of main with our pixel (row 0 at the top).
void LaneProbeBegin(int px, int py) {
    gGroupKey = ((py / 2) * uBlocksX + px / 4) * uNumTriangles + gl_PrimitiveID;
    if (IsFirstActiveLane()) {
        atomicAdd(gGroupRuns, 1u);
        atomicMax(gSubgroupSize, uint(gl_SubGroupSizeARB));
    }
    if (readFirstInvocationARB(gGroupKey) != gGroupKey) atomicAdd(gShapeViolations, 1u);
}
