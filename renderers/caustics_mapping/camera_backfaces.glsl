// Pass 5a: the closed dielectrics' back faces from the camera (Wyman 2005, "An
// Approximate Image-Space Approach for Interactive Refraction": the second surface
// is rendered from the eye at the camera's resolution, and the view ray refracted at
// the front surface looks up its exit there). The camera pass (camera.glsl) reads it.
//
// Two RGBA32F attachments per camera pixel, row 0 at the bottom (GL):
//   0: xyz world position (m) of the nearest back face, w = object index + 1
//      (0: no back face of a closed dielectric in this pixel);
//   1: xyz unit normal as stored in the mesh (outward: closed meshes), w = 0.
// (surface_positions.glsl writes them; u_vp is the scene camera's world -> clip.)
// Back faces are the triangles facing away from the eye by their winding (closed
// meshes are counter-clockwise seen from outside): the pass culls the front ones.
// Of several, the depth test keeps the nearest, where a view ray that entered the
// object through a front face first leaves it. (The winding, not the interpolated
// normal: at a silhouette a front triangle's interpolated normal can point away from
// the eye, and would hide the true exit behind a point on the front surface.)

#include "surface_positions.glsl"

#if defined FRAGMENT_SHADER
void main() {
    write_surface(normalize(v_normal));
}
#endif
