// The Gaussians program of a splat pass (splat_kernels.glsl: kernels `points` and
// `footprint`, and the quarters `triangles` cannot draw), included by
// caustic_splat.glsl and receiver_splat.glsl when TRIANGLES is not defined: a
// compute pass sets up one Gaussian per trace record, then one vertex per record
// draws it as a square point sprite over every target pixel the Gaussian's cut-off
// ellipse reaches. With c the hit in target pixels, S the
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
#if defined VERTEX_SHADER || defined COMPUTE_SHADER
// Each record's Gaussian (binding 5, three vec4 per record), set up by the compute
// pass (gaussian_setup below) and drawn by the vertex shader: the set-up's loops
// (the norm's pixels, the neighbours' hits) run on every thread the driver has,
// where llvmpipe shades a draw's vertices on one (glass_sphere, strong: caustic map
// 32 -> 29 ms on 2 cores; renders unchanged, bit for bit):
//   0: xy c (target pixels), z sprite size (pixels), w 1 if drawn (else 0)
//   1: S^-1 (target pixels^-2), columns xy and zw
//   2: rgb value (W/m^2 at weight 1), w 0
layout(std430, binding = 5) buffer GaussianSplats { vec4 gaussians[]; };
#endif

#if defined COMPUTE_SHADER
layout(local_size_x = 64) in;
uniform int u_count;            // records (invocations past it do nothing)
// The Gaussian of record i: false where it draws nothing (not splatted here, no
// share left by the triangles, or no pixel within its cut-off).
bool gaussian_setup(int i, out vec2 c, out mat2 inv, out vec3 value, out float size) {
    c = vec2(0.0);
    inv = mat2(1.0);
    value = vec3(0.0);
    size = 0.0;
    if (!to_target(i, c)) return false;
    int view, tx, ty;
    record_vertex(i, view, tx, ty);
    float share = gaussian_share(view, tx, ty);
    if (share <= 0.0) return false;
    vec3 hit = splat_records[i * 5 + 2].xyz;
    vec3 normal = splat_records[i * 5 + 4].xyz;
    mat2 cov = gaussian_covariance(view, tx, ty, hit, normal, c);
    float radius = fit_radius(cov, u_cut, u_max_radius);
    inv = inverse(cov);
    vec2 lo, hi;
    target_bounds(lo, hi);
    float norm = gaussian_norm(c, inv, radius, u_cut, lo, hi);
    if (!(norm > 0.0)) return false;
    value = gaussian_value(share * splat_records[i * 5 + 3].rgb, norm, hit, normal);
    // The sprite covers the pixel centres within ceil(radius) of c: every texel the
    // cut-off ellipse reaches.
    size = 2.0 * ceil(radius) + 1.0;
    return true;
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_count) return;
    vec2 c;
    mat2 inv;
    vec3 value;
    float size;
    bool drawn = gaussian_setup(i, c, inv, value, size);
    gaussians[i * 3] = vec4(c, size, drawn ? 1.0 : 0.0);
    gaussians[i * 3 + 1] = vec4(inv[0], inv[1]);
    gaussians[i * 3 + 2] = vec4(value, 0.0);
}
#elif defined VERTEX_SHADER
flat out vec3 v_value;       // W/m^2 at weight 1
flat out vec2 v_center;      // c (target pixels)
flat out mat2 v_inverse;     // S^-1 (target pixels^-2)
void main() {
    vec4 head = gaussians[gl_VertexID * 3];
    vec4 inv = gaussians[gl_VertexID * 3 + 1];
    v_value = gaussians[gl_VertexID * 3 + 2].rgb;
    v_center = head.xy;
    v_inverse = mat2(inv.xy, inv.zw);
    gl_PointSize = max(head.z, 1.0);
    gl_Position = head.w > 0.5 ? target_position(head.xy)
                               : vec4(2.0, 2.0, 2.0, 1.0);   // culled
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
