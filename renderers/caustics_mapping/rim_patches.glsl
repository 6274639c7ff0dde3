// Pass 3a, rim patches: which grid quads the caustic trace traces again as patches
// (caustic_trace.glsl, u_patches). Where the light grazes an object's silhouette its
// refraction bends fast: glass_sphere's outer grid rings spread over 1 to 4 m of
// floor, and its quads there are far from the flat pieces their triangles draw (the
// halo's streaks and horseshoes). A quad is patched when it shows the object (not
// all four corners empty) and a corner lies within RIM_STEPS grid steps (along the
// grid's axes) of a vertex that shows none (status empty; the grid's border counts
// as empty) or is one.
//
// BAND (one invocation per quad): handoff[q] = 1 for a patched quad, else 0; the
// splat passes leave patched quads to their patches (splat_triangles.glsl).
// LIST (one work group): the patched quads in increasing order (patch_quads) and
// their number (patch_count[0]), which the renderer reads back.
#include "common.glsl"

layout(std430, binding = 0) readonly buffer Records { vec4 records[]; };
layout(std430, binding = 1) buffer Handoff { int handoff[]; };
layout(std430, binding = 2) buffer PatchQuads { int patch_quads[]; };
layout(std430, binding = 3) buffer PatchCount { int patch_count[]; };

uniform int u_grid;             // vertex grid per object view
uniform int u_count;            // quads (views * (grid - 1)^2)

// glass_sphere strong at grid 128, patches of 3 x 3, excess relMSE over the whole
// floor [caustic region]: 1 step 2.2e-4 [5.8e-5]; 2 steps 1.2e-4 [1.1e-4]; 3 steps
// 1.0e-4 [1.5e-4]: wider bands reach farther in, where a patch's curved edge and its
// unpatched neighbour's straight one leave a seam across the caustic.
const int RIM_STEPS = 1;

#if defined BAND
layout(local_size_x = 64) in;

bool empty_vertex(int view, int x, int y) {
    if (x < 0 || y < 0 || x >= u_grid || y >= u_grid) return true;
    return records[((view * u_grid + y) * u_grid + x) * 5 + 2].w < 0.5;
}

bool near_empty(int view, int x, int y) {
    if (empty_vertex(view, x, y)) return true;
    for (int step = 1; step <= RIM_STEPS; ++step)
        if (empty_vertex(view, x + step, y) || empty_vertex(view, x - step, y)
            || empty_vertex(view, x, y + step) || empty_vertex(view, x, y - step))
            return true;
    return false;
}

void main() {
    int q = int(gl_GlobalInvocationID.x);
    if (q >= u_count) return;
    int side = u_grid - 1;
    int view = q / (side * side), local = q - view * side * side;
    int qx = local % side, qy = local / side;
    bool all_empty = true, near = false;
    for (int k = 0; k < 4; ++k) {
        int x = qx + (k == 1 || k == 2 ? 1 : 0), y = qy + (k >= 2 ? 1 : 0);
        all_empty = all_empty && empty_vertex(view, x, y);
        near = near || near_empty(view, x, y);
    }
    handoff[q] = !all_empty && near ? 1 : 0;
}
#else  // LIST
layout(local_size_x = 1024) in;
#include "compact.glsl"

bool compact_listed(int q) { return handoff[q] != 0; }
void compact_store(int slot, int q) { patch_quads[slot] = q; }
void compact_total(int count) { patch_count[0] = count; }

void main() { compact(u_count); }
#endif
