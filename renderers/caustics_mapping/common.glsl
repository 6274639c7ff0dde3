// Shared GLSL of the caustics-mapping passes (included by every .glsl here).
//
// Conventions
// -----------
// * World space is right-handed metres, +z up.
// * A "map atlas" stores the light's map views side by side: the view in slot s
//   occupies the texels x in [s*size, (s+1)*size); u_map_slot[face] is a view's
//   slot, -1 for cube faces that see no receiver (not stored: nothing there). A
//   point light has six cube faces (+x, -x, +y, -y, +z, -z; a direction's face is
//   its major axis), spot and directional lights one view.
// * The receiver positions atlas is RGBA32F: xyz world position (m), w receiver
//   index + 1 (0 = no receiver seen in that texel). Its companion attachments hold
//   the receiver normal (xyz) and the receiver (u, v) (xy).
// * Lookups are nearest-texel (texelFetch) or, with `lookup = "filtered"`, bilinear
//   between the four nearest texels when all four show the same surface (same w),
//   else nearest. The NumPy mirror in estimators.py does the same arithmetic.

const int STATUS_EMPTY = 0;     // no caustic object at this grid texel
const int STATUS_HIT = 1;       // splatted
const int STATUS_LOST = 2;      // a lookup found no receiver: splat dropped
const int STATUS_TIR = 3;       // total internal reflection at the exit surface
const int STATUS_DIVERGED = 4;  // the estimator produced a non-finite update
const int STATUS_NO_EXIT = 5;   // double refraction found no exit surface
const int STATUS_UNCONVERGED = 6;  // verified hits: residual above tolerance, or no
                                   // receiver at the estimate
const int STATUS_REENTERED = 7; // the exit (or reflected) ray meets its object again

// Whether a record is splatted: a hit, or (u_splat_unconverged) an unverified
// estimate that still lies on a receiver (record fields: status, receiver index).
uniform int u_splat_unconverged;
bool splatted(float status, float receiver) {
    int code = int(status + 0.5);
    return code == STATUS_HIT
        || (u_splat_unconverged == 1 && code == STATUS_UNCONVERGED && receiver > -0.5);
}

// ---------------------------------------------------------------- the light
uniform int u_light_type;      // 0 point, 1 spot, 2 directional
uniform vec3 u_light_pos;      // m (point, spot)
uniform vec3 u_light_dir;      // travel direction / spot axis / area-sample normal
uniform vec3 u_light_power;    // I (W/sr) or E0 (W/m^2)
uniform vec4 u_spot;           // cos cutoff, cos beam, cutoff (rad), beam (rad)
uniform int u_lambertian;      // 1: intensity * max(cos, 0) about u_light_dir

// ---------------------------------------------------------------- map views
uniform mat4 u_map_vp[6];
uniform int u_map_cube;        // 1: six cube faces, else one view
uniform int u_map_slot[6];     // atlas slot of each view, -1: not stored
uniform int u_map_persp;       // 1 perspective, 0 orthographic
uniform vec4 u_map_rect;       // x0, x1, y0, y1 on the view plane: tangents or m

// Unit direction light travels at x.
vec3 incident_dir(vec3 x) {
    return u_light_type == 2 ? u_light_dir : normalize(x - u_light_pos);
}

// Distance (m) of x from the light along its ray; for a directional light the signed
// distance dot(x, u_light_dir) (the shadow map's r channel).
float light_distance(vec3 x) {
    return u_light_type == 2 ? dot(x, u_light_dir) : length(x - u_light_pos);
}

// Relative intensity along the unit travel direction l: spot cone (linear in angle
// between beam width and cutoff, like Mitsuba's spot) and the Lambertian cosine of
// an area-light sample. The ramp is clamped to [0, 1]: just inside the cutoff
// (c > cos cutoff) a single-precision acos(c) can exceed the cutoff angle by its
// rounding (llvmpipe's acos: ~1e-4 rad), which would make the intensity, and every
// irradiance and flux derived from it, negative.
float light_falloff(vec3 l) {
    float f = 1.0;
    if (u_light_type == 1) {
        float c = dot(l, u_light_dir);
        if (c <= u_spot.x) return 0.0;
        if (c < u_spot.y)
            f = clamp((u_spot.z - acos(clamp(c, -1.0, 1.0))) / (u_spot.z - u_spot.w), 0.0, 1.0);
    }
    if (u_lambertian == 1) f *= max(dot(l, u_light_dir), 0.0);
    return f;
}

// Direct irradiance (W/m^2) on a surface at x with unit normal n, no occlusion.
vec3 direct_irradiance(vec3 x, vec3 n) {
    vec3 l = incident_dir(x);
    float c = max(dot(n, -l), 0.0);
    if (u_light_type == 2) return u_light_power * c;
    vec3 dx = x - u_light_pos;
    return u_light_power * light_falloff(l) * c / max(dot(dx, dx), 1e-30);
}

// Cube face of direction d: major axis, ties broken x, then y, then z.
int cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0 ? 0 : 1;
    if (a.y >= a.z) return d.y >= 0.0 ? 2 : 3;
    return d.z >= 0.0 ? 4 : 5;
}

// Normalised device coordinates of x in view vp; false behind or outside it.
bool project(mat4 vp, vec3 x, out vec2 ndc) {
    vec4 c = vp * vec4(x, 1.0);
    ndc = vec2(0.0);
    if (!(c.w > 0.0)) return false;
    ndc = c.xy / c.w;
    return abs(ndc.x) <= 1.0 && abs(ndc.y) <= 1.0;
}

// The atlas texel of NDC `ndc` in view `face` of a map with `size` texels per side.
ivec2 map_texel(int face, vec2 ndc, int size) {
    ivec2 t = min(ivec2(floor((ndc * 0.5 + 0.5) * float(size))), ivec2(size - 1));
    return ivec2(max(u_map_slot[face], 0) * size + t.x, t.y);
}

// Locates x in the map views: its face and NDC; false when x is outside every view
// (or in a view that is not stored). map_locate's first half, for callers that
// look x up in several maps (one projection, then map_texel per map size).
bool map_project(vec3 x, out int face, out vec2 ndc) {
    face = u_map_cube == 1 ? cube_face(x - u_light_pos) : 0;
    bool inside = project(u_map_vp[face], x, ndc);
    return inside && u_map_slot[face] >= 0;
}

// Locates x in the map views: its face, NDC, and the atlas texel of a map with
// `size` texels per face side. False when x is outside every view.
bool map_locate(vec3 x, int size, out int face, out vec2 ndc, out ivec2 texel) {
    bool found = map_project(x, face, ndc);
    texel = map_texel(face, ndc, size);
    return found;
}

// Solid angle (sr, perspective) or area perpendicular to the light (m^2,
// orthographic) of one texel of a view of `size` x `size` texels spanning `rect` =
// (x0, x1, y0, y1) on the view plane, at NDC `ndc`. With texel sides
// s = (x1 - x0, y1 - y0) / size and the texel's view-plane point p at unit distance:
// d_omega = s.x s.y / (1 + |p|^2)^(3/2) (foreshortened by cos^3), or s.x s.y.
float texel_measure(int persp, vec4 rect, int size, vec2 ndc) {
    vec2 s = vec2(rect.y - rect.x, rect.w - rect.z) / float(size);
    if (persp == 0) return s.x * s.y;
    vec2 t = ndc * 0.5 + 0.5;
    vec2 p = vec2(mix(rect.x, rect.y, t.x), mix(rect.z, rect.w, t.y));
    float q = 1.0 + dot(p, p);
    return s.x * s.y / (q * sqrt(q));
}

// Width (m) of one texel of a map view of `size` texels per side at point x:
// the view-plane texel width times x's distance from the light (perspective), or the
// texel width itself (orthographic).
float map_texel_width(vec3 x, int size) {
    float w = max(u_map_rect.y - u_map_rect.x, u_map_rect.w - u_map_rect.z) / float(size);
    return u_map_persp == 0 ? w : w * length(x - u_light_pos);
}

// Bilinear lookup in one face (atlas slot `slot`, `size` texels per side) at face
// pixel coordinates `pix` (texel centres at k + 0.5). The four texels around `pix`
// are blended only when their w (a surface tag: receiver or object index + 1) is the
// same and non-zero; otherwise `ok` is false and the nearest texel stands alone.
struct Bilinear {
    ivec2 t00;        // atlas texel of the lower-left of the four
    vec2 f;           // blend weights along x and y
    ivec2 nearest;    // atlas texel containing pix
    bool ok;          // blend (else read `nearest`)
    float tag;        // with ok: the four texels' common tag (the nearest one's)
};

// bilinear_at on the W x H block of texels from `base` (an atlas face or a whole
// image).
Bilinear bilinear_block(sampler2D tagged, ivec2 base, ivec2 size, vec2 pix) {
    Bilinear b;
    vec2 q = clamp(pix - 0.5, vec2(0.0), vec2(size - 1));
    ivec2 i0 = min(ivec2(floor(q)), max(size - 2, ivec2(0)));
    b.f = q - vec2(i0);
    b.t00 = base + i0;
    b.nearest = base + min(ivec2(floor(pix)), size - 1);
    float w00 = texelFetch(tagged, b.t00, 0).w;
    float w10 = texelFetch(tagged, b.t00 + ivec2(1, 0), 0).w;
    float w01 = texelFetch(tagged, b.t00 + ivec2(0, 1), 0).w;
    float w11 = texelFetch(tagged, b.t00 + ivec2(1, 1), 0).w;
    b.ok = size.x >= 2 && size.y >= 2 && w00 > 0.5 && abs(w10 - w00) < 0.5
        && abs(w01 - w00) < 0.5 && abs(w11 - w00) < 0.5;
    b.tag = w00;
    return b;
}

Bilinear bilinear_at(sampler2D tagged, int slot, int size, vec2 pix) {
    return bilinear_block(tagged, ivec2(slot * size, 0), ivec2(size), pix);
}

// `tex` read through b: blended, or the nearest texel. A blended read's w is the
// common tag (exact for a tagged image; a companion image's w is not used).
vec4 bilinear_read(sampler2D tex, Bilinear b) {
    if (!b.ok) return texelFetch(tex, b.nearest, 0);
    vec4 a = mix(texelFetch(tex, b.t00, 0), texelFetch(tex, b.t00 + ivec2(1, 0), 0), b.f.x);
    vec4 c = mix(texelFetch(tex, b.t00 + ivec2(0, 1), 0),
                 texelFetch(tex, b.t00 + ivec2(1, 1), 0), b.f.x);
    vec4 r = mix(a, c, b.f.y);
    r.w = b.tag;                       // the tag is never blended
    return r;
}

// A surface image read at face pixel coordinates `pix` of atlas slot `slot` (`size`
// texels per side): `positions` RGBA32F (xyz m, w surface tag) into p, its companion
// `normals` (xyz unit) into n. Nearest texel, or (`filtered`) bilinear within one
// surface (bilinear_at) with the blended normal renormalised.
void surface_read(sampler2D positions, sampler2D normals, int slot, int size, vec2 pix,
                  bool filtered, out vec4 p, out vec3 n) {
    if (filtered) {
        Bilinear b = bilinear_at(positions, slot, size, pix);
        p = bilinear_read(positions, b);
        n = bilinear_read(normals, b).xyz;
        if (dot(n, n) > 0.0) n = normalize(n);
    } else {
        ivec2 t = ivec2(slot * size, 0) + min(ivec2(floor(pix)), ivec2(size - 1));
        p = texelFetch(positions, t, 0);
        n = texelFetch(normals, t, 0).xyz;
    }
}

// T(x): the receiver the light sees through x in the receiver positions atlas
// `positions` (`size` texels per face; layout above), position t (w: receiver + 1)
// and unit normal n from its companion `normals`; false where none is seen.
bool receiver_lookup(sampler2D positions, sampler2D normals, int size, bool filtered, vec3 x,
                     out vec4 t, out vec3 n) {
    int face;
    vec2 ndc;
    t = vec4(0.0);
    n = vec3(0.0);
    if (!map_project(x, face, ndc)) return false;
    surface_read(positions, normals, u_map_slot[face], size, (ndc * 0.5 + 0.5) * float(size),
                 filtered, t, n);
    return t.w > 0.5;
}

// Area (m^2) on the receiver covered by one caustic-map texel around hit x with
// receiver normal n: the texel's solid angle times distance^2 (or its perpendicular
// area) over |cos| between n and the light ray, the cosine clamped at 1e-3.
float map_texel_area(vec3 x, vec3 n, vec2 ndc, int size) {
    vec3 l = incident_dir(x);
    float c = max(abs(dot(n, l)), 1e-3);
    float m = texel_measure(u_map_persp, u_map_rect, size, ndc);
    if (u_map_persp == 0) return m / c;
    vec3 dx = x - u_light_pos;
    return m * dot(dx, dx) / c;
}

// Unpolarised Fresnel transmittance for cos_i = cos of the incidence angle (> 0),
// from index eta_i into eta_t; 0 beyond the critical angle.
float fresnel_transmittance(float cos_i, float eta_i, float eta_t) {
    float eta = eta_i / eta_t;
    float sin_t2 = eta * eta * max(1.0 - cos_i * cos_i, 0.0);
    if (sin_t2 >= 1.0) return 0.0;
    float cos_t = sqrt(1.0 - sin_t2);
    float rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    float rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}
