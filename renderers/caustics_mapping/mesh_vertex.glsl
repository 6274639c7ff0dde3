// The vertex stage of the passes that rasterise the scene's meshes (the positions
// passes, surface_positions.glsl; the shadow map; the camera): each vertex's world
// position (m) and normal (as stored in the mesh) pass through unchanged, and
//     gl_Position = u_vp (position, 1).
// With MESH_UV defined the vertex's receiver (u, v) passes through as well. In the
// fragment stage this file declares the interpolated inputs v_position, v_normal (not
// renormalised) and, with MESH_UV, v_uv.
uniform mat4 u_vp;          // world -> clip of the view being drawn

#if defined VERTEX_SHADER
in vec3 in_position;
in vec3 in_normal;
out vec3 v_position;
out vec3 v_normal;
#if defined MESH_UV
in vec2 in_uv;
out vec2 v_uv;
#endif
void main() {
    v_position = in_position;
    v_normal = in_normal;
#if defined MESH_UV
    v_uv = in_uv;
#endif
    gl_Position = u_vp * vec4(in_position, 1.0);
}
#elif defined FRAGMENT_SHADER
in vec3 v_position;
in vec3 v_normal;
#if defined MESH_UV
in vec2 v_uv;
#endif
#endif
