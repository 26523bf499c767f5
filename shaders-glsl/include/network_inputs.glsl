// What every network variant shares: the network's shape, its activation, the 13 raw inputs
// of a pixel (in the order of `raw_inputs` in baker/src/network.rs), and the G-buffer,
// materials and lights bindings they are read from (network_interface.glsl).
#ifndef RRF_NETWORK_INPUTS_GLSL
#define RRF_NETWORK_INPUTS_GLSL

// INPUTS, HIDDEN1, HIDDEN2, the parameter offsets: generated from baker/src/network_layout.rs.
#include "network_layout.glsl"

#include "gbuffer_layout.glsl"
#include "network_interface.glsl"
#include "mirror_weights.glsl"

layout(binding = SURFACE_BINDING, rgba32ui) uniform readonly uimage2D gbuffer_surface;
layout(binding = ID_BINDING, r32ui) uniform readonly uimage2D gbuffer_id;
// Per material: rgb emitted radiance (before the emissive texture), w the
// KHR_materials_specular factor.
layout(std430, binding = MATERIALS_BINDING) readonly buffer Materials { vec4 materials[]; };
layout(binding = SHADING_BINDING, rgba32ui) uniform readonly uimage2D gbuffer_shading;
// The frame's lights, as many as the push constants' `light_count`: copies of the moving
// light, each at `position.xyz`, each scaling the networks' output by `scale.rgb`. Light
// transport is linear in the emission, so the pixel's radiance is the sum over the copies.
// Before them, the eyes (xyz) of the camera reflected in each mirror the frame shows.
struct Light {
    vec4 position;
    vec4 scale;
};
layout(std430, binding = LIGHTS_BINDING) readonly buffer Lights {
    vec4 mirror_eyes[MAX_MIRRORS];
    Light lights[];
};

// Where a pixel is seen from: the camera `camera`, or where the G-buffer shows what a mirror
// reflects, the camera reflected in the mirror's plane, with the mirror's Fresnel weight.
struct Viewer {
    vec3 eye;
    bool mirrored;
    vec3 fresnel;
};

Viewer pixel_viewer(uint id, ivec2 pixel, vec3 camera) {
    if (!id_reflected(id)) {
        return Viewer(camera, false, vec3(1.0));
    }
    vec4 mirror = imageLoad(mirror_weights, pixel);
    return Viewer(mirror_eyes[uint(mirror.a)].xyz, true, mirror.rgb);
}

// The material's textured values at `pixel`: read once per pixel and passed to the functions
// below (lavapipe gathers every image read lane by lane).
Shading pixel_shading(ivec2 pixel) {
    return decode_shading(imageLoad(gbuffer_shading, pixel));
}

// What the surface of G-buffer id `id` and shading `s` emits towards the viewer.
vec3 surface_emission(uint id, Shading s) {
    return materials[id_material(id)].rgb * s.emissive_texture;
}

// What the networks' outputs are multiplied by: the surface's reflectance, the twin of
// `reflectance` in baker/src/network.rs.
vec3 surface_reflectance(uint id, Shading s) {
    float specular = materials[id_material(id)].w;
    vec3 diffuse = s.base_color * (1.0 - s.metallic);
    vec3 f0 = mix(vec3(0.04 * specular), s.base_color, s.metallic);
    return max(diffuse + f0, vec3(MIN_REFLECTANCE));
}

// tanh as x·P(x²)/Q(x²) on [-9, 9], a rational least-squares fit made for rrf (maximum
// absolute error 5.3e-6; tanh(±9) is ±1 to 3e-8). On lavapipe it costs about half of the
// driver's exp-based tanh, which was 40% of the network pass. The CPU inference keeps the
// exact tanh; tests/network_pass.rs holds the two together.
float network_tanh(float x) {
    float c = clamp(x, -9.0, 9.0);
    float t = c * c;
    float p = fma(fma(fma(2.95279086521e-6, t, 0.00204361631518), t, 0.120238358696), t, 0.999976417795);
    float q = fma(fma(fma(0.000118331687614, t, 0.0199404181136), t, 0.453501095597), t, 1.0);
    return clamp(c * p / q, -1.0, 1.0);
}

// Position, direction towards the eye, shading normal, roughness, of the surface at `pixel`
// with shading `s`; the light position's three inputs (from LIGHT_INPUT) are left 0, for the
// loop over the lights to fill in.
float[INPUTS] raw_inputs(ivec2 pixel, Shading s, vec3 eye) {
    uvec4 surface = imageLoad(gbuffer_surface, pixel);
    vec3 p = uintBitsToFloat(surface.xyz);
    vec3 n = decode_normal(surface.w);
    vec3 v = normalize(eye - p);
    float roughness = s.roughness;
    return float[INPUTS](p.x, p.y, p.z, v.x, v.y, v.z, 0.0, 0.0, 0.0, n.x, n.y, n.z, roughness);
}

#endif
