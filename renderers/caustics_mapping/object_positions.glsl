// Caustic-object positions and normals from the light at the vertex-grid
// resolution (paper Section 3.2, second pass; back faces for Wyman's image-space
// double refraction). Two RGBA32F attachments per object-atlas texel:
//   0: xyz world position (m), w = object index + 1 (0: no object);
//   1: xyz unit normal as stored in the mesh (outward for closed meshes), w = 0.
// BACK_FACES: keep only surfaces facing away from the light (the exit surface).
#include "common.glsl"

uniform mat4 u_vp;
uniform int u_object;

#if defined VERTEX_SHADER
in vec3 in_position;
in vec3 in_normal;
out vec3 v_position;
out vec3 v_normal;
void main() {
    v_position = in_position;
    v_normal = in_normal;
    gl_Position = u_vp * vec4(in_position, 1.0);
}
#elif defined FRAGMENT_SHADER
in vec3 v_position;
in vec3 v_normal;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
void main() {
    vec3 n = normalize(v_normal);
#if defined BACK_FACES
    // Exit surface: the outward normal points along the light's travel direction.
    if (dot(n, incident_dir(v_position)) <= 0.0) discard;
#endif
    out_position = vec4(v_position, float(u_object + 1));
    out_normal = vec4(n, 0.0);
}
#endif
