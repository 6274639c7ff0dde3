// Receiver positions from the light (paper Section 3.2, first pass).
// Three attachments per map-atlas texel (RGBA32F, RGBA32F, RG32F; the first two
// written as in surface_positions.glsl):
//   0: xyz world position (m), w = receiver index + 1 (0: no receiver);
//   1: xyz unit receiver normal, w = 0;
//   2: xy receiver (u, v) (receiver units).
#include "common.glsl"

#define MESH_UV 1
#include "surface_positions.glsl"

#if defined FRAGMENT_SHADER
layout(location = 2) out vec4 out_uv;
void main() {
    write_surface(normalize(v_normal));
    out_uv = vec4(v_uv, 0.0, 0.0);
}
#endif
