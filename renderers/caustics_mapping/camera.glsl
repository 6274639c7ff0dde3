// Pass 5: the final camera pass (paper Section 3.2). Output RGBA32F: rgb linear
// radiance (W m^-2 sr^-1), a = 1 where geometry was drawn.
//
// Receivers are Lambertian: L = albedo / pi * (E_direct * visibility + E_caustic),
// E_direct only when the scene has direct lighting, visibility from the shadow map
// only with the shadows effect, E_caustic looked up in the caustic map at the
// fragment's projection into the light's view (like a shadow-map lookup). The
// caustic map holds the irradiance of the receiver the light sees in that texel, so
// it is used only where the positions atlas shows this very fragment (same receiver,
// within three positions texels).
// OBJECT: the caustic object, drawn with the refraction approximation: the view ray
// is refracted (dielectric) or reflected (conductor) once at the surface and shaded
// where it meets the first receiver's plane; black where it meets none.
#include "common.glsl"

uniform mat4 u_camera_vp;
uniform vec3 u_eye;
uniform vec3 u_albedo;
uniform int u_receiver;
uniform int u_direct;              // scene has direct lighting
uniform int u_shadows;             // shadows effect
uniform int u_caustics;            // a caustic map is bound
uniform sampler2D u_shadow_map;    // RG32F: r light distance, g coverage
uniform int u_shadow_size;
uniform float u_shadow_bias;       // m
uniform sampler2D u_caustic_map;   // RGBA32F: rgb E (W/m^2)
uniform int u_caustic_size;
uniform sampler2D u_positions;     // receiver positions atlas
uniform int u_positions_size;
// OBJECT variant
uniform int u_material;            // 1, 2 dielectric, 3 conductor
uniform float u_ior;
uniform vec3 u_reflectance;
uniform vec4 u_plane;              // receiver 0's plane: n.x = w
uniform vec3 u_plane_albedo;

float light_distance(vec3 x) {
    return u_light_type == 2 ? dot(x, u_light_dir) : length(x - u_light_pos);
}

vec3 receiver_radiance(vec3 x, vec3 n, vec3 albedo, int receiver) {
    vec3 e = vec3(0.0);
    int face;
    vec2 ndc;
    // One projection into the light's views serves the three map lookups.
    bool found = map_project(x, face, ndc);
    if (u_direct == 1) {
        float visible = 1.0;
        if (u_shadows == 1 && found) {
            vec4 s = texelFetch(u_shadow_map, map_texel(face, ndc, u_shadow_size), 0);
            if (s.g > 0.5 && s.r < light_distance(x) - u_shadow_bias) visible = 0.0;
        }
        e += visible * direct_irradiance(x, n);
    }
    if (u_caustics == 1 && found) {
        vec4 p = texelFetch(u_positions, map_texel(face, ndc, u_positions_size), 0);
        float tol = 3.0 * sqrt(map_texel_area(x, n, ndc, u_positions_size));
        if (int(p.w + 0.5) - 1 == receiver && length(p.xyz - x) <= tol) {
            e += texelFetch(u_caustic_map, map_texel(face, ndc, u_caustic_size), 0).rgb;
        }
    }
    return albedo / 3.14159265358979 * e;
}

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
out vec4 out_radiance;
void main() {
    vec3 n = normalize(v_normal);
#if defined OBJECT
    vec3 d = normalize(v_position - u_eye);
    if (dot(n, d) > 0.0) n = -n;
    vec3 r = u_material == 3 ? reflect(d, n) : refract(d, n, 1.0 / u_ior);
    vec3 weight = u_material == 3 ? u_reflectance : vec3(1.0);
    if (dot(r, r) == 0.0) r = reflect(d, n);
    vec3 color = vec3(0.0);
    float den = dot(u_plane.xyz, r);
    if (den != 0.0) {
        float t = (u_plane.w - dot(u_plane.xyz, v_position)) / den;
        if (t > 0.0) {
            vec3 y = v_position + t * r;
            color = weight * receiver_radiance(y, u_plane.xyz, u_plane_albedo, 0);
        }
    }
    out_radiance = vec4(color, 1.0);
#else
    out_radiance = vec4(receiver_radiance(v_position, n, u_albedo, u_receiver), 1.0);
#endif
}
#endif
