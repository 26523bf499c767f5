// Analytic direct light (`--direct analytic`, the RRF paper's mode for point lights): the
// direct light of the frame's point lights at a surface, from the baker's BRDF (brdf.glsl),
// with visibility from the cube shadow maps (shadow_cube.glsl). It is the path tracer's
// next-event estimate of a point light (`integrator.rs`), with a shadow map for the ray.
//
// The including shader declares `lights` (network_inputs.glsl), `shadow_atlas` and the push
// constants `light_intensity`, `spot_axis` and `spot_cos_outer`.
#ifndef RRF_ANALYTIC_DIRECT_GLSL
#define RRF_ANALYTIC_DIRECT_GLSL

#include "brdf.glsl"
#include "shadow_cube.glsl"

// The share of light `light`'s cube map that sees `p` (a surface point of normal `n`): 2×2
// texels, bilinearly weighted. The point is moved off its surface by one texel along the
// normal, so that a lit surface does not shadow itself at the map's resolution.
float shadow_visibility(uint light, vec3 p, vec3 n) {
    vec3 light_position = lights[light].position.xyz;
    float texel = 2.0 * distance(p, light_position) / float(SHADOW_SIZE);
    vec3 d = p + n * texel - light_position;
    uint face = cube_face_of(d);
    vec4 clip = cube_face_clip(d, face);
    vec2 t = (clip.xy / clip.w * 0.5 + 0.5) * float(SHADOW_SIZE) - 0.5;
    vec2 corner = floor(t);
    vec2 w = t - corner;
    ivec2 origin = ivec2(face * SHADOW_SIZE, light * SHADOW_SIZE);
    float mine = length(d);
    float lit = 0.0;
    for (int j = 0; j < 2; ++j) {
        for (int i = 0; i < 2; ++i) {
            ivec2 q = clamp(ivec2(corner) + ivec2(i, j), ivec2(0), ivec2(SHADOW_SIZE - 1));
            float nearest = imageLoad(shadow_atlas, origin + q).r;
            float weight = (i == 0 ? 1.0 - w.x : w.x) * (j == 0 ? 1.0 - w.y : w.y);
            lit += mine <= nearest + 0.5 * texel ? weight : 0.0;
        }
    }
    return lit;
}

// glTF's spot falloff (`Cone::attenuation`) towards `to` (unit, from the light); 1 for a
// point light (spot_axis.xyz = 0).
float spot_attenuation(vec3 to) {
    if (constants.spot_axis.xyz == vec3(0.0)) {
        return 1.0;
    }
    float scale = 1.0 / max(constants.spot_axis.w - constants.spot_cos_outer, 1e-3);
    float t = clamp((dot(constants.spot_axis.xyz, to) - constants.spot_cos_outer) * scale, 0.0, 1.0);
    return t * t;
}

// Direct light leaving `p` (normal `n`, towards the viewer `wo`) of material `s` with
// KHR_materials_specular factor `specular`, summed over the frame's lights.
vec3 analytic_direct(vec3 p, vec3 n, vec3 wo, Shading s, float specular) {
    vec3 sum = vec3(0.0);
    for (uint l = 0u; l < constants.light_count; ++l) {
        vec3 to_light = lights[l].position.xyz - p;
        float d2 = dot(to_light, to_light);
        vec3 wi = to_light * inversesqrt(d2);
        float cos_i = dot(n, wi);
        float spot = spot_attenuation(-wi);
        if (cos_i <= 0.0 || spot == 0.0) {
            continue;
        }
        vec3 f = brdf_eval(s.base_color, s.metallic, s.roughness, specular, n, wo, wi);
        float visible = shadow_visibility(l, p, n);
        sum += f * constants.light_intensity.rgb * lights[l].scale.rgb * (spot * cos_i / d2 * visible);
    }
    return sum;
}

#endif
