// Caustic-object positions and normals from the light at the vertex-grid
// resolution (paper Section 3.2, second pass; back faces for Wyman's image-space
// double refraction). Two RGBA32F attachments per object-atlas texel
// (surface_positions.glsl):
//   0: xyz world position (m), w = object index + 1 (0: no object);
//   1: xyz unit normal as stored in the mesh (outward for closed meshes), w = 0.
// BACK_FACES: keep only surfaces facing away from the light (the exit surface).
#include "common.glsl"
#include "surface_positions.glsl"

#if defined FRAGMENT_SHADER
void main() {
    vec3 n = normalize(v_normal);
#if defined BACK_FACES
    // Exit surface: the outward normal points along the light's travel direction.
    if (dot(n, incident_dir(v_position)) <= 0.0) discard;
#endif
    write_surface(n);
}
#endif
