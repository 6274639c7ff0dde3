// Pass 3a, rim patches: which grid quads the caustic trace traces again as patches
// (caustic_trace.glsl, u_patches). Where the light grazes an object's silhouette its
// refraction bends fast: glass_sphere's outer grid rings spread over 1 to 4 m of
// floor, and its quads there are far from the flat pieces their triangles draw (the
// halo's streaks and horseshoes). A quad is patched when it shows the object (not
// all four corners empty), a corner lies within RIM_STEPS grid steps (along the
// grid's axes) of a vertex that shows none (status empty; the grid's border counts
// as empty) or is one, or reflects off a conductor near grazing (`grazing`), and a
// corner's light leaves the object (`leaves`).
//
// A mirror's reflection turns twice as fast as its normal, and near grazing a step
// across the light's rays moves the normal by 1 / |l . n| times as much, so the
// reflected rays fan out fastest where |l . n| is small, wherever that lies: a
// bowl's outer wall at its terminator is inside the silhouette band only where the
// wall is the outline. There the whole floor caustic of the concave family's bowls
// under a high sun starts (bowl_deep_sun75, grid 128: 0.5 % of the floor's flux from
// |l . n| < 0.02, 5.7 % from 0.02-0.05, 28.6 % from 0.05-0.12, 65.2 % from
// 0.12-0.3, none above).
//
// BAND (one invocation per quad): handoff[q] = 1 for a patched quad, else 0; the
// splat passes leave patched quads to their patches (splat_triangles.glsl).
// LIST (one work group): the patched quads in increasing order (patch_quads) and
// their number (patch_count[0]), which the renderer reads back; a patched quad's
// handoff becomes its patch's index + 1.
//
// Neighbouring patches share the vertices of their common edges (a third of all
// patch vertices on glass_sphere and bunny), which the trace would trace twice to
// the same record. Each is traced once, in its owner: of the patched quads that
// have it as a corner, the one of lowest index.
// OWNED (one invocation per patch vertex, record order): owner[s], the record of
// vertex s in its owner's patch (s itself where it owns it).
// UNIQUE (one work group): the owned records in increasing order (unique_slots), and
// the trace's dispatch over them (groups x, y, z, and their count).
// COPY (one invocation per patch vertex): a record not owned, and its history, copied
// from its owner's after the trace.
#include "common.glsl"

#if defined COPY
layout(std430, binding = 0) buffer Records { vec4 records[]; };
layout(std430, binding = 7) buffer History { float history[]; };
#else
layout(std430, binding = 0) readonly buffer Records { vec4 records[]; };
#endif
layout(std430, binding = 1) buffer Handoff { int handoff[]; };
layout(std430, binding = 2) buffer PatchQuads { int patch_quads[]; };
layout(std430, binding = 3) buffer PatchCount { int patch_count[]; };
layout(std430, binding = 4) buffer Owner { int owner[]; };
layout(std430, binding = 5) buffer UniqueSlots { int unique_slots[]; };
layout(std430, binding = 6) buffer UniqueDispatch { uint unique_dispatch[4]; };

uniform int u_grid;             // vertex grid per object view
uniform int u_count;            // quads (views * (grid - 1)^2); patch vertices (OWNED,
                                // UNIQUE, COPY)
uniform int u_factor;           // patch quads per grid quad side (OWNED, COPY)
uniform int u_history;          // history floats per record (COPY)
uniform int u_exits_only;       // 1: a patched quad has a corner that `leaves` (BAND)
uniform int u_share;            // 1: shared vertices traced once (OWNED); 0: every copy
uniform float u_grazing;        // a conductor corner with |l . n| below it is in the
                                // band (BAND); 0: none

// glass_sphere strong at grid 128, patches of 3 x 3, excess relMSE over the whole
// floor [caustic region]: 1 step 2.2e-4 [5.8e-5]; 2 steps 1.2e-4 [1.1e-4]; 3 steps
// 1.0e-4 [1.5e-4]: wider bands reach farther in, where a patch's curved edge and its
// unpatched neighbour's straight one leave a seam across the caustic.
const int RIM_STEPS = 1;

#if defined BAND
layout(local_size_x = 64) in;

// The status code of grid vertex (x, y) of `view` (inside the grid).
int status_of(int view, int x, int y) {
    return int(records[((view * u_grid + y) * u_grid + x) * 5 + 2].w + 0.5);
}

bool empty_vertex(int view, int x, int y) {
    if (x < 0 || y < 0 || x >= u_grid || y >= u_grid) return true;
    return status_of(view, x, y) == STATUS_EMPTY;
}

// Whether the light of a vertex that shows the object leaves it along an exit (or
// reflected) ray: every status but total internal reflection and no exit surface.
// A rim quad whose corners all keep their light inside (the bunny's silhouette band
// from the light is mostly TIR) is left to the grid: 545 of the bunny's 1,250 rim
// quads have a corner that leaves, and its patches' hit vertices go from 3,604 to
// 3,568, for its patches' trace 12.4 -> 4.4 ms a frame on llvmpipe (receiver excess
// relMSE 5.651e-3 -> 5.647e-3, caustic region 0.08956 -> 0.08953); every rim quad of
// glass_sphere and metal_ring has one.
bool leaves(int view, int x, int y) {
    int status = status_of(view, x, y);     // a quad's corners lie inside the grid
    if (u_exits_only == 0) return status != STATUS_EMPTY;
    return status != STATUS_EMPTY && status != STATUS_TIR && status != STATUS_NO_EXIT;
}

// Whether a vertex reflects off a conductor with |l . n| < u_grazing (record 4's w,
// caustic_trace.glsl: -1 at every vertex that does not reflect off one).
bool grazing(int view, int x, int y) {
    float c = records[((view * u_grid + y) * u_grid + x) * 5 + 4].w;
    return c >= 0.0 && c < u_grazing;
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
    bool near = false, exits = false;
    for (int k = 0; k < 4; ++k) {
        int x = qx + (k == 1 || k == 2 ? 1 : 0), y = qy + (k >= 2 ? 1 : 0);
        near = near || near_empty(view, x, y) || grazing(view, x, y);
        exits = exits || leaves(view, x, y);
    }
    // A corner that leaves shows the object, so the quad is not all empty.
    handoff[q] = near && exits ? 1 : 0;
}
#elif defined OWNED
layout(local_size_x = 64) in;

void main() {
    int s = int(gl_GlobalInvocationID.x);
    if (s >= u_count) return;
    int side = u_factor + 1, quads = u_grid - 1;
    int k = s / (side * side), local = s - k * side * side;
    int i = local % side, j = local / side;
    int q = patch_quads[k];
    int view = q / (quads * quads), within = q - view * quads * quads;
    int qx = within % quads, qy = within / quads;
    // The patched quads with this vertex as a corner: q, and its neighbours across
    // the patch edges the vertex lies on.
    int best = q;
    ivec2 at = ivec2(qx, qy);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            if ((dx == -1 && i != 0) || (dx == 1 && i != u_factor)
                || (dy == -1 && j != 0) || (dy == 1 && j != u_factor)) continue;
            int cx = qx + dx, cy = qy + dy;
            if (cx < 0 || cy < 0 || cx >= quads || cy >= quads) continue;
            int c = (view * quads + cy) * quads + cx;
            if (handoff[c] != 0 && c < best) {
                best = c;
                at = ivec2(cx, cy);
            }
        }
    }
    ivec2 there = ivec2(i, j) - u_factor * (at - ivec2(qx, qy));
    owner[s] = best == q || u_share == 0 ? s
        : (handoff[best] - 1) * side * side + there.y * side + there.x;
}
#elif defined COPY
layout(local_size_x = 64) in;

void main() {
    int s = int(gl_GlobalInvocationID.x);
    if (s >= u_count) return;
    int o = owner[s];
    if (o == s) return;
    for (int m = 0; m < 5; ++m) records[s * 5 + m] = records[o * 5 + m];
    for (int m = 0; m < u_history; ++m)
        history[s * u_history + m] = history[o * u_history + m];
}
#else  // LIST, UNIQUE
layout(local_size_x = 1024) in;
#include "compact.glsl"

#if defined UNIQUE
bool compact_listed(int s) { return owner[s] == s; }
void compact_store(int slot, int s) { unique_slots[slot] = s; }
void compact_total(int count) {
    unique_dispatch = uint[4](uint((count + 63) / 64), 1u, 1u, uint(count));
}
#else
bool compact_listed(int q) { return handoff[q] != 0; }
void compact_store(int slot, int q) {
    patch_quads[slot] = q;
    handoff[q] = slot + 1;
}
void compact_total(int count) { patch_count[0] = count; }
#endif

void main() { compact(u_count); }
#endif
