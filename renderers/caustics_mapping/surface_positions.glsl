// The outputs shared by the positions passes (receiver_positions.glsl,
// object_positions.glsl, camera_backfaces.glsl), which draw meshes with the vertex
// stage of mesh_vertex.glsl. Two RGBA32F attachments per texel:
//   0: xyz world position (m) of the nearest surface drawn, w = u_index + 1
//      (0: nothing drawn in this texel);
//   1: xyz unit normal as stored in the mesh (outward for closed meshes), w = 0.
// Each pass writes them with write_surface() from its own fragment main.
#include "mesh_vertex.glsl"

uniform int u_index;        // the mesh drawn: object or receiver index

#if defined FRAGMENT_SHADER
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

// Attachments 0 and 1 at this fragment, with unit normal n.
void write_surface(vec3 n) {
    out_position = vec4(v_position, float(u_index + 1));
    out_normal = vec4(n, 0.0);
}
#endif
