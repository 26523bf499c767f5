// Network pass, step 2 of the specialized variants: one pipeline per network unit (an object,
// or the part of one in a box: network_units.glsl), with the unit's direct and indirect
// weights as specialization constants (see build.rs), so the driver compiles them into the
// code as immediates.
//
// TILED: the dispatch is indirect, one workgroup per tile that network_classify.comp listed
// for this unit. Otherwise it covers the whole image and skips other units' pixels.
//
// With DISPLAY defined (network_display.comp) the pass writes only what the window shows: the
// chosen component, tonemapped, into one RGBA8 image. Otherwise it writes the direct, indirect
// and global radiance as RGBA32F images, for read-back.
//
// Where the G-buffer shows what a planar mirror reflects, the pixel is seen from the camera
// reflected in the mirror and weighted by its Fresnel term (network_inputs.glsl).
//
// ANALYTIC: direct light is computed (analytic_direct.glsl), not learned; the direct network
// is compiled out.
//
// Where the unit's weight is below one (network_units.glsl: a band where kd-tree leaves
// blend), the units that meet there add their weighted radiance in the order they are
// dispatched, with a barrier between dispatches: the first stores, the others load and add.
// Only the radiance images blend; the host gives DISPLAY pipelines no blending units.
#ifndef RRF_NETWORK_SPECIALIZED_MAIN_GLSL
#define RRF_NETWORK_SPECIALIZED_MAIN_GLSL

layout(local_size_x = 8, local_size_y = 8) in;

#include "network_interface.glsl"

// The G-buffer's object value (object id + 1) this pipeline shades.
layout(constant_id = OBJECT_ID) const uint OBJECT = 1u;
layout(constant_id = TILED_ID) const bool TILED = true;
layout(constant_id = ANALYTIC_ID) const bool ANALYTIC = false;
// Whether the frame has more than one light: a pipeline of each kind, because lavapipe runs
// the networks about 50% slower inside a loop, even one that runs once, and most frames have
// one light (BENCHMARKS.md, "Several lights").
layout(constant_id = SEVERAL_LIGHTS_ID) const bool SEVERAL_LIGHTS = false;
// The unit's index (its tile list and its entry in the unit table), its object's first unit,
// and the number of object entries in the unit table (network_units.glsl).
layout(constant_id = UNIT_ID) const uint UNIT = 0u;
layout(constant_id = OBJECT_FIRST_UNIT_ID) const uint OBJECT_FIRST_UNIT = 0u;
layout(constant_id = OBJECTS_ID) const uint OBJECTS = 1u;

// The G-buffer, materials and lights: network_inputs.glsl. Binding numbers:
// network_interface.glsl.
layout(binding = TILES_BINDING) readonly buffer Tiles { uint tiles[]; };
#ifdef DISPLAY
layout(binding = FIRST_OUTPUT_BINDING, rgba8) uniform writeonly image2D display;
#define OUTPUT_IMAGES 1
#else
layout(binding = FIRST_OUTPUT_BINDING, rgba32f) uniform image2D out_direct;
layout(binding = FIRST_OUTPUT_BINDING + 1, rgba32f) uniform image2D out_indirect;
layout(binding = FIRST_OUTPUT_BINDING + 2, rgba32f) uniform image2D out_gi;
#define OUTPUT_IMAGES 3
#endif
// The point lights' cube shadow maps (ANALYTIC; a 1×1 stand-in otherwise).
layout(binding = FIRST_OUTPUT_BINDING + OUTPUT_IMAGES, r32f) uniform readonly image2D shadow_atlas;
#define UNITS_BINDING (FIRST_OUTPUT_BINDING + OUTPUT_IMAGES + 1)

layout(push_constant) uniform Constants {
    vec4 eye;
    uint light_count;
    uint tile_capacity;
    // DISPLAY only: 2^EV, and the component shown (0 global, 1 direct, 2 indirect).
    float exposure_scale;
    uint shown;
    // ANALYTIC only: the trained point light's intensity (W/sr, rgb); for a spot light its axis
    // (xyz) and the cosines of its inner (w) and outer cone angles, else an axis of 0.
    vec4 light_intensity;
    vec4 spot_axis;
    float spot_cos_outer;
} constants;

#include "network_inputs.glsl"
#include "network_units.glsl"
#include "specialized_networks.glsl"
#include "analytic_direct.glsl"
#ifdef DISPLAY
#include "tonemap.glsl"
#endif

// Whether a unit of this pipeline's object dispatched before this one has a weight at `p`.
bool earlier_units_weigh(vec3 p) {
    for (uint u = OBJECT_FIRST_UNIT; u < UNIT; ++u) {
        if (unit_weight(OBJECTS, u, p) > 0.0) {
            return true;
        }
    }
    return false;
}

void main() {
    uvec2 tile = gl_WorkGroupID.xy;
    if (TILED) {
        uint packed = tiles[UNIT * constants.tile_capacity + gl_WorkGroupID.x];
        tile = uvec2(packed & 0xffffu, packed >> 16);
    }
    ivec2 pixel = ivec2(tile * gl_WorkGroupSize.xy + gl_LocalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(gbuffer_id)))) {
        return;
    }
    uint id = imageLoad(gbuffer_id, pixel).r;
    if (id_object(id) != OBJECT) {
        return;
    }
    Shading shading = pixel_shading(pixel);
    Viewer viewer = pixel_viewer(id, pixel, constants.eye.xyz);
    float x[INPUTS] = raw_inputs(pixel, shading, viewer.eye);
    vec3 p = vec3(x[0], x[1], x[2]);
    float weight = unit_weight(OBJECTS, UNIT, p);
    if (weight == 0.0) {
        return;
    }
    vec3 direct = vec3(0.0);
    vec3 indirect = vec3(0.0);
    if (!SEVERAL_LIGHTS) {
        for (int i = 0; i < 3; ++i) {
            x[LIGHT_INPUT + i] = lights[0].position[i];
        }
        if (!ANALYTIC) {
            direct = direct_network(x) * lights[0].scale.rgb;
        }
        indirect = indirect_network(x) * lights[0].scale.rgb;
    } else {
        // The lights share the first layer's per-pixel part.
        float direct_sums[HIDDEN1];
        float indirect_sums[HIDDEN1];
        if (!ANALYTIC) {
            direct_surface(x, direct_sums);
        }
        indirect_surface(x, indirect_sums);
        for (uint l = 0u; l < constants.light_count; ++l) {
            vec3 light = lights[l].position.xyz;
            if (!ANALYTIC) {
                direct += direct_lit(direct_sums, light) * lights[l].scale.rgb;
            }
            indirect += indirect_lit(indirect_sums, light) * lights[l].scale.rgb;
        }
    }
    vec3 reflectance = surface_reflectance(id, shading);
    direct *= reflectance;
    indirect *= reflectance;
    if (ANALYTIC) {
        vec3 wo = vec3(x[3], x[4], x[5]);
        vec3 n = vec3(x[9], x[10], x[11]);
        direct = analytic_direct(p, n, wo, shading, materials[id_material(id)].w);
    }
    vec3 emission = surface_emission(id, shading);
    if (viewer.mirrored) {
        seen_in_mirror(viewer.fresnel, emission, direct, indirect);
    }
#ifdef DISPLAY
    vec3 shown = constants.shown == 1u ? direct
               : constants.shown == 2u ? indirect
               : emission + direct + indirect;
    imageStore(display, pixel, vec4(tonemap(shown, constants.exposure_scale), 1.0));
#else
    vec3 gi = emission + direct + indirect;
    if (weight < 1.0) {
        direct *= weight;
        indirect *= weight;
        gi *= weight;
        if (earlier_units_weigh(p)) {
            direct += imageLoad(out_direct, pixel).rgb;
            indirect += imageLoad(out_indirect, pixel).rgb;
            gi += imageLoad(out_gi, pixel).rgb;
        }
    }
    imageStore(out_direct, pixel, vec4(direct, 1.0));
    imageStore(out_indirect, pixel, vec4(indirect, 1.0));
    imageStore(out_gi, pixel, vec4(gi, 1.0));
#endif
}

#endif
