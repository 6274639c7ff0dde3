// Shadow map (paper Section 3.2, optional fourth pass): the caustic objects' light
// distance per map-atlas texel. RG32F: r = distance from the light along the ray
// (m; for a directional light the signed distance dot(x, direction)), g = 1 where
// an object was seen (0: nothing, fully lit).
#include "common.glsl"

uniform mat4 u_vp;

// Distance of x from the light along its ray (shared with camera.glsl).
#if defined VERTEX_SHADER
in vec3 in_position;
out vec3 v_position;
void main() {
    v_position = in_position;
    gl_Position = u_vp * vec4(in_position, 1.0);
}
#elif defined FRAGMENT_SHADER
in vec3 v_position;
out vec4 out_depth;
void main() {
    float dist = u_light_type == 2 ? dot(v_position, u_light_dir) : length(v_position - u_light_pos);
    out_depth = vec4(dist, 1.0, 0.0, 0.0);
}
#endif
