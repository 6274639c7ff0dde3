// Shadow map (paper Section 3.2, optional fourth pass): the caustic objects' light
// distance per map-atlas texel. RG32F: r = distance from the light along the ray
// (m; for a directional light the signed distance dot(x, direction)), g = 1 where
// an object was seen (0: nothing, fully lit).
#include "common.glsl"
#include "mesh_vertex.glsl"

#if defined FRAGMENT_SHADER
out vec4 out_depth;
void main() {
    out_depth = vec4(light_distance(v_position), 1.0, 0.0, 0.0);
}
#endif
