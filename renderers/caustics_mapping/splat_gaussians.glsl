// The Gaussians program of a splat pass (splat_kernels.glsl: kernels `points` and
// `footprint`, and the quarters `triangles` cannot draw), included by
// caustic_splat.glsl and receiver_splat.glsl when TRIANGLES is not defined: one
// vertex per trace record, drawn as a square point sprite over every target pixel
// the Gaussian's cut-off ellipse reaches. With c the hit in target pixels, S the
// covariance (target pixels^2) and q = x - c for a pixel centre x, the pixel gets
//     w = exp(-q^T S^-1 q / 2)   where q^T S^-1 q <= u_cut^2 (else nothing),
//     rgb = value * w,  a = w,   value = share * flux / (norm * A):
// norm is the sum of w over the splat's pixels on the target (gaussian_norm), so the
// weights sum to one and the vertex's flux share is kept; A (m^2) is the receiver
// area of one target pixel at the hit, so rgb is irradiance (W/m^2).
// The including pass defines, before including this file,
//   vec4 target_position(vec2 pix)     target pixels -> clip position
//   mat2 gaussian_covariance(int view, int tx, int ty, vec3 hit, vec3 normal, inout vec2 c)
//                                      S of the record of grid vertex (view, tx, ty),
//                                      hit P (m) with receiver normal `normal`, at
//                                      target pixel c (which it may move onto the
//                                      target)
//   void target_bounds(out vec2 lo, out vec2 hi)
//                                      the target's pixels [lo, hi) (one face of an
//                                      atlas)
//   vec3 gaussian_value(vec3 flux, float norm, vec3 hit, vec3 normal)
//                                      flux / (norm * A): `value` above
#if defined VERTEX_SHADER
in vec4 in_hit;              // record entry 2: xyz P (m), w status
in vec4 in_flux;             // record entry 3: rgb flux (W), w receiver index
in vec4 in_normal;           // record entry 4: xyz receiver normal at P
flat out vec3 v_value;       // W/m^2 at weight 1
flat out vec2 v_center;      // c (target pixels)
flat out mat2 v_inverse;     // S^-1 (target pixels^-2)
void main() {
    v_value = vec3(0.0);
    v_center = vec2(0.0);
    v_inverse = mat2(1.0);
    gl_PointSize = 1.0;
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);              // culled unless set below
    vec2 c;
    if (!to_target(gl_VertexID, c)) return;
    int per_view = u_grid * u_grid;                       // record -> (view, tx, ty)
    int view = gl_VertexID / per_view;
    int local = gl_VertexID - view * per_view;
    int tx = local % u_grid, ty = local / u_grid;
    float share = gaussian_share(view, tx, ty);
    if (share <= 0.0) return;
    mat2 cov = gaussian_covariance(view, tx, ty, in_hit.xyz, in_normal.xyz, c);
    float radius = fit_radius(cov, u_cut, u_max_radius);
    mat2 inv = inverse(cov);
    vec2 lo, hi;
    target_bounds(lo, hi);
    float norm = gaussian_norm(c, inv, radius, u_cut, lo, hi);
    if (!(norm > 0.0)) return;
    v_value = gaussian_value(share * in_flux.rgb, norm, in_hit.xyz, in_normal.xyz);
    v_center = c;
    v_inverse = inv;
    // The sprite covers the pixel centres within ceil(radius) of c: every texel the
    // cut-off ellipse reaches.
    gl_PointSize = 2.0 * ceil(radius) + 1.0;
    gl_Position = target_position(c);
}
#elif defined FRAGMENT_SHADER
flat in vec3 v_value;
flat in vec2 v_center;
flat in mat2 v_inverse;
out vec4 out_irradiance;
void main() {
    vec2 q = gl_FragCoord.xy - v_center;
    float e = dot(q, v_inverse * q);                      // q^T S^-1 q
    if (e > u_cut * u_cut) discard;
    float w = exp(-0.5 * e);
    out_irradiance = vec4(v_value * w, w);
}
#endif
