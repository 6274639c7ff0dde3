// Pass 3c: splat the same trace records into one receiver's (u, v) irradiance map
// (DESIGN.md, radiometric contract). Row 0 of the target is v = vmin, column 0
// u = umin.
//
// Output (RGBA32F, u_map_size texels): rgb caustic irradiance E (W/m^2 of receiver
// surface, like the reference's photon tracer), a = splat weight.
// (u, v) of a hit P: an affine map of P when the receiver's (u, v) are affine in
// position (planes, heightfields), else the (u, v) the positions pass stored at P's
// texel. The Gaussian has the footprint the splat has in the caustic map:
// sigma = u_sigma caustic-map texels, converted to metres on the receiver and then
// to (u, v) texels; every splat's weights are normalised to sum to one over the
// map, so the flux splatted here equals the flux splatted into the caustic map.
#include "common.glsl"

uniform int u_receiver;
uniform int u_caustic_size;        // caustic-map texels per face (footprint)
uniform int u_positions_size;      // positions-atlas texels per face (uv lookup)
uniform sampler2D u_uv_texture;    // positions-pass attachment 2: xy (u, v)
uniform int u_uv_affine;           // 1: (u, v) = (dot(u_row_u, P,1), dot(u_row_v, P,1))
uniform vec4 u_row_u;
uniform vec4 u_row_v;
uniform float u_uv_per_metre;
uniform vec4 u_extent;             // umin, umax, vmin, vmax
uniform ivec2 u_map_size;          // W, H
uniform float u_sigma;             // caustic-map texels
uniform float u_cut;               // sigmas
uniform float u_max_radius;        // pixels

#if defined VERTEX_SHADER
in vec4 in_hit;
in vec4 in_flux;
in vec4 in_normal;
flat out vec3 v_value;
flat out vec2 v_center;
flat out vec2 v_sigma;
void main() {
    v_value = vec3(0.0);
    v_center = vec2(0.0);
    v_sigma = vec2(1.0);
    gl_PointSize = 1.0;
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    if (int(in_hit.w + 0.5) != STATUS_HIT || int(in_flux.w + 0.5) != u_receiver) return;
    int face;
    vec2 ndc;
    ivec2 texel;
    if (!map_locate(in_hit.xyz, u_caustic_size, face, ndc, texel)) return;
    float metres = u_sigma * sqrt(map_texel_area(in_hit.xyz, in_normal.xyz, ndc, u_caustic_size));
    vec2 uv;
    if (u_uv_affine == 1) {
        uv = vec2(dot(u_row_u, vec4(in_hit.xyz, 1.0)), dot(u_row_v, vec4(in_hit.xyz, 1.0)));
    } else {
        map_locate(in_hit.xyz, u_positions_size, face, ndc, texel);
        uv = texelFetch(u_uv_texture, texel, 0).xy;
    }
    vec2 size = vec2(u_map_size);
    vec2 span = vec2(u_extent.y - u_extent.x, u_extent.w - u_extent.z);
    // Map pixels. A hit whose estimate P lies just off the (u, v) domain (its lookup
    // found this receiver, so it is at the edge) is clamped onto the border texels,
    // so no flux is lost between the caustic map and this map.
    vec2 c = clamp((uv - u_extent.xz) / span * size, vec2(0.5), size - 0.5);
    vec2 sigma = max(metres * u_uv_per_metre / span * size, vec2(0.5));
    sigma = min(sigma, vec2(u_max_radius / u_cut));
    float norm = splat_norm(c, sigma, u_cut, vec2(0.0), size);
    if (!(norm > 0.0)) return;
    float texel_area = span.x * span.y / (size.x * size.y);        // (u, v) units^2
    // Irradiance is per unit *surface* area: divide by the surface area per unit
    // (u, v) area, J = dA / (du dv). For affine (u, v) = (a.P + c, b.P + d) on a
    // surface of normal n, du dv = |(a x b) . n| dA, so J = 1 / |(a x b) . n|
    // (1 on a plane; 1 / |n_z| on a heightfield). Otherwise use the mesh's mean.
    float jacobian = 1.0 / (u_uv_per_metre * u_uv_per_metre);
    if (u_uv_affine == 1) {
        float c = abs(dot(cross(u_row_u.xyz, u_row_v.xyz), normalize(in_normal.xyz)));
        jacobian = 1.0 / max(c, 1e-6);
    }
    v_value = in_flux.rgb / (norm * texel_area * jacobian);
    v_center = c;
    v_sigma = sigma;
    // Pixel centres within ceil(cut * sigma) of c: every texel the cut-off reaches.
    gl_PointSize = 2.0 * ceil(u_cut * max(sigma.x, sigma.y)) + 1.0;
    gl_Position = vec4(c / size * 2.0 - 1.0, 0.0, 1.0);
}
#elif defined FRAGMENT_SHADER
flat in vec3 v_value;
flat in vec2 v_center;
flat in vec2 v_sigma;
out vec4 out_irradiance;
void main() {
    float w = splat_weight(gl_FragCoord.xy, v_center, v_sigma, u_cut);
    if (w < 0.0) discard;
    out_irradiance = vec4(v_value * w, w);
}
#endif
