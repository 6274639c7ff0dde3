// Caustic-object positions and normals from the light at the vertex-grid
// resolution (paper Section 3.2, second pass; back faces for Wyman's image-space
// double refraction). Two RGBA32F attachments per object-atlas texel
// (surface_positions.glsl):
//   0: xyz world position (m), w = object index + 1 (0: no object);
//   1: xyz unit normal as stored in the mesh (outward for closed meshes), w = 0;
//   2: xyz unit geometric normal n_g of the triangle drawn, on the side of the stored
//      normal (for the adjoint shading-normal factor), w = 0.
// BACK_FACES: keep only surfaces facing away from the light (the exit surface).
#include "common.glsl"
#include "surface_positions.glsl"

#if defined FRAGMENT_SHADER
layout(location = 2) out vec4 out_geometric;

void main() {
    vec3 n = normalize(v_normal);
#if defined BACK_FACES
    // Exit surface: the outward normal points along the light's travel direction.
    if (dot(n, incident_dir(v_position)) <= 0.0) discard;
#endif
    write_surface(n);
    // The position is linear over the triangle, so its screen derivatives (taken over
    // the 2 x 2 quad, helper invocations on the same triangle) span its plane exactly.
    vec3 g = cross(dFdx(v_position), dFdy(v_position));
    float len = length(g);
    g = len > 0.0 ? g / len : n;
    out_geometric = vec4(dot(g, n) < 0.0 ? -g : g, 0.0);
}
#endif
