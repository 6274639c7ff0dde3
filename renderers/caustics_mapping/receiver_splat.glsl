// Pass 3c: splat the same trace records into one receiver's (u, v) irradiance map
// (radiometric contract: W per m² of receiver surface), with the kernels of splat_kernels.glsl. The
// map is the receiver's slot of an atlas (viewport and scissor set to it; its first
// column u_map_origin): row 0 is v = vmin, its column 0 u = umin.
//
// Output (RGBA32F, u_map_size texels): rgb caustic irradiance E (W/m^2 of receiver
// surface, like the reference's photon tracer), a = kernel weight.
// (u, v) of a hit P: an affine map of P when the receiver's (u, v) are affine in
// position (planes, heightfields), else the (u, v) the positions pass stored at P's
// texel. A `points` Gaussian has the footprint the splat has in the caustic map:
// sigma = u_sigma caustic-map texels, converted to metres on the receiver and then
// to (u, v) texels; a footprint Gaussian is shaped by its neighbours' (u, v) here.
// Every kernel's weights sum to one over the map, so each vertex's flux is kept.
// Irradiance is per unit *surface* area: flux per (u, v) area divided by the surface
// area per (u, v) area, J = dA / (du dv). For affine (u, v) = (a.P + c, b.P + d) on
// a surface of normal n, du dv = |(a x b) . n| dA, so J = 1 / |(a x b) . n| (1 on a
// plane; 1 / |n_z| on a heightfield). Otherwise the mesh's mean is used.
#include "common.glsl"

uniform int u_receiver;
uniform int u_caustic_size;        // caustic-map texels per face (points footprint)
uniform int u_positions_size;      // positions-atlas texels per face (uv lookup)
uniform sampler2D u_uv_texture;    // positions-pass attachment 2: xy (u, v)
uniform int u_uv_affine;           // 1: (u, v) = (dot(u_row_u, P,1), dot(u_row_v, P,1))
uniform vec4 u_row_u;
uniform vec4 u_row_v;
uniform float u_uv_per_metre;
uniform vec4 u_extent;             // umin, umax, vmin, vmax
uniform ivec2 u_map_size;          // W, H of the receiver's slot
uniform int u_map_origin;          // the slot's first column in the atlas (pixels)

#include "splat_kernels.glsl"

#if defined VERTEX_SHADER || defined GEOMETRY_SHADER || defined COMPUTE_SHADER
vec2 uv_span() {                    // umax - umin, vmax - vmin
    return vec2(u_extent.y - u_extent.x, u_extent.w - u_extent.z);
}

vec2 uv_of(vec3 x) {
    if (u_uv_affine == 1)
        return vec2(dot(u_row_u, vec4(x, 1.0)), dot(u_row_v, vec4(x, 1.0)));
    int face;
    vec2 ndc;
    ivec2 texel;
    map_locate(x, u_positions_size, face, ndc, texel);
    return texelFetch(u_uv_texture, texel, 0).xy;
}

// The record's hit in atlas pixels (its slot's from u_map_origin), when it is
// splatted onto receiver u_receiver.
bool to_target(int record, out vec2 pix) {
    pix = vec2(0.0);
    vec4 hit = splat_records[record * 5 + 2];
    float receiver = splat_records[record * 5 + 3].w;
    if (!splatted(hit.w, receiver) || int(receiver + 0.5) != u_receiver) return false;
    vec2 span = uv_span();
    pix = (uv_of(hit.xyz) - u_extent.xz) / span * vec2(u_map_size)
        + vec2(float(u_map_origin), 0.0);
    return true;
}

vec4 target_position(vec2 pix) {     // the viewport is the slot
    vec2 slot_pix = pix - vec2(float(u_map_origin), 0.0);
    return vec4(slot_pix / vec2(u_map_size) * 2.0 - 1.0, 0.0, 1.0);
}

// Surface area per (u, v) area at a point of unit normal n (see the header).
float uv_jacobian(vec3 n) {
    if (u_uv_affine == 0) return 1.0 / (u_uv_per_metre * u_uv_per_metre);
    return 1.0 / max(abs(dot(cross(u_row_u.xyz, u_row_v.xyz), n)), 1e-6);
}

float texel_area() {                // (u, v) units^2
    vec2 span = uv_span();
    return span.x * span.y / float(u_map_size.x * u_map_size.y);
}
#endif

#if defined TRIANGLES
#if defined GEOMETRY_SHADER || defined COMPUTE_SHADER
// Surface area of a triangle: its map pixels times the (u, v) area of a pixel times
// the surface area per (u, v) area at the receiver normal n.
float triangle_area(vec2 a, vec2 b, vec2 c, vec3 pa, vec3 pb, vec3 pc, vec3 n) {
    vec2 e1 = b - a, e2 = c - a;
    return 0.5 * abs(e1.x * e2.y - e1.y * e2.x) * texel_area() * uv_jacobian(n);
}
#endif
#include "splat_triangles.glsl"
#else  // Gaussians
#if defined COMPUTE_SHADER
// points: the width the splat has in the caustic map, u_sigma caustic-map texels at
// the hit, in metres on the receiver, in (u, v), in map pixels (at least half a
// pixel per axis); footprint: the grid's hit differences, that width where none is
// known. A hit whose estimate P lies just off the (u, v) domain (its lookup found
// this receiver, so it is at the edge) is clamped onto the border texels, so no
// flux is lost between the caustic map and this map.
mat2 gaussian_covariance(int view, int tx, int ty, vec3 hit, vec3 normal, inout vec2 c) {
    vec2 size = vec2(u_map_size);
    vec2 span = uv_span();
    int face;
    vec2 ndc;
    ivec2 texel;
    map_locate(hit, u_caustic_size, face, ndc, texel);
    float metres = u_sigma * sqrt(map_texel_area(hit, normal, ndc, u_caustic_size));
    vec2 sigma = max(metres * u_uv_per_metre / span * size, vec2(0.5));
    vec2 origin = vec2(float(u_map_origin), 0.0);
    c = clamp(c, origin + 0.5, origin + size - 0.5);
    return u_splat_mode == SPLAT_POINTS ? mat2(sigma.x * sigma.x, 0.0, 0.0, sigma.y * sigma.y)
        : footprint_covariance(view, tx, ty, c, max(sigma.x, sigma.y));
}

void target_bounds(out vec2 lo, out vec2 hi) {      // the slot
    lo = vec2(float(u_map_origin), 0.0);
    hi = lo + vec2(u_map_size);
}

// A = one map pixel's (u, v) area times the surface area per (u, v) area.
vec3 gaussian_value(vec3 flux, float norm, vec3 hit, vec3 normal) {
    return flux / (norm * texel_area() * uv_jacobian(normalize(normal)));
}
#endif
#include "splat_gaussians.glsl"
#endif
