// Pass 5a: the closed dielectrics' back faces from the camera (Wyman 2005, "An
// Approximate Image-Space Approach for Interactive Refraction": the second surface
// is rendered from the eye at the camera's resolution, and the view ray refracted at
// the front surface looks up its exit there). The camera pass (camera.glsl) reads it.
//
// Two RGBA32F attachments per camera pixel, row 0 at the bottom (GL):
//   0: xyz world position (m) of the nearest back face, w = object index + 1
//      (0: no back face of a closed dielectric in this pixel);
//   1: xyz unit normal as stored in the mesh (outward: closed meshes), w = 0.
// Back faces are the triangles facing away from the eye by their winding (closed
// meshes are counter-clockwise seen from outside): the pass culls the front ones.
// Of several, the depth test keeps the nearest, where a view ray that entered the
// object through a front face first leaves it. (The winding, not the interpolated
// normal: at a silhouette a front triangle's interpolated normal can point away from
// the eye, and would hide the true exit behind a point on the front surface.)

uniform mat4 u_camera_vp;  // world -> clip of the scene camera
uniform int u_object;      // object index

#if defined VERTEX_SHADER
in vec3 in_position;
in vec3 in_normal;
out vec3 v_position;
out vec3 v_normal;
void main() {
    v_position = in_position;
    v_normal = in_normal;
    gl_Position = u_camera_vp * vec4(in_position, 1.0);
}
#elif defined FRAGMENT_SHADER
in vec3 v_position;
in vec3 v_normal;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
void main() {
    out_position = vec4(v_position, float(u_object + 1));
    out_normal = vec4(normalize(v_normal), 0.0);
}
#endif
