// Receiver positions from the light (paper Section 3.2, first pass).
// Three attachments per map-atlas texel (RGBA32F, RGBA32F, RG32F):
//   0: xyz world position (m), w = receiver index + 1 (0: no receiver);
//   1: xyz unit receiver normal, w = 0;
//   2: xy receiver (u, v) (receiver units).
#include "common.glsl"

uniform mat4 u_vp;        // world -> clip of the face being rendered
uniform int u_receiver;   // receiver index

#if defined VERTEX_SHADER
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_uv = in_uv;
    gl_Position = u_vp * vec4(in_position, 1.0);
}
#elif defined FRAGMENT_SHADER
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_uv;
void main() {
    out_position = vec4(v_position, float(u_receiver + 1));
    out_normal = vec4(normalize(v_normal), 0.0);
    out_uv = vec4(v_uv, 0.0, 0.0);
}
#endif
