#version 450
#extension GL_GOOGLE_include_directive : require
// Network pass, weights in a storage buffer: per pixel, the 13 inputs from the G-buffer and
// the constants, then the direct and indirect networks of the pixel's units (network_units.glsl),
// summed over the lights and weighted by the units' blend weights.
//
// Where the G-buffer shows what a planar mirror reflects, the pixel is seen from the camera
// reflected in the mirror and weighted by its Fresnel term (network_inputs.glsl).
//
// Per unit, UNIT_STRIDE floats: the direct parameters, then the indirect parameters, each with
// the input normalisation and the output scale folded in.

layout(local_size_x = 8, local_size_y = 8) in;

#include "network_interface.glsl"

// Whether the frame has more than one light: a pipeline of each kind, as in
// network_specialized_main.glsl.
layout(constant_id = SEVERAL_LIGHTS_ID) const bool SEVERAL_LIGHTS = false;

// The G-buffer, materials and lights: network_inputs.glsl. Binding numbers:
// network_interface.glsl.
layout(binding = WEIGHTS_BINDING) readonly buffer Weights { float weights[]; };
layout(binding = FIRST_OUTPUT_BINDING, rgba32f) uniform writeonly image2D out_direct;
layout(binding = FIRST_OUTPUT_BINDING + 1, rgba32f) uniform writeonly image2D out_indirect;
layout(binding = FIRST_OUTPUT_BINDING + 2, rgba32f) uniform writeonly image2D out_gi;

layout(push_constant) uniform Constants {
    vec4 eye;
    uint light_count;
    uint objects;
} constants;

#include "network.glsl"
#define UNITS_BINDING (FIRST_OUTPUT_BINDING + 3)
#include "network_units.glsl"

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(out_gi)))) {
        return;
    }
    uint id = imageLoad(gbuffer_id, pixel).r;
    uint object = id_object(id);
    Shading shading = pixel_shading(pixel);
    vec3 emission = object > 0u ? surface_emission(id, shading) : vec3(0.0);
    vec3 direct = vec3(0.0);
    vec3 indirect = vec3(0.0);
    Viewer viewer = pixel_viewer(id, pixel, constants.eye.xyz);
    uvec2 range = object > 0u ? object_units(object - 1u) : uvec2(0u);
    if (range.y > 0u) {
        float x[INPUTS] = raw_inputs(pixel, shading, viewer.eye);
        vec3 p = vec3(x[0], x[1], x[2]);
        for (uint unit = range.x; unit < range.x + range.y; ++unit) {
            float weight = unit_weight(constants.objects, unit, p);
            if (weight == 0.0) {
                continue;
            }
            uint base = unit * UNIT_STRIDE;
            vec3 unit_direct = vec3(0.0);
            vec3 unit_indirect = vec3(0.0);
            if (!SEVERAL_LIGHTS) {
                for (int i = 0; i < 3; ++i) {
                    x[LIGHT_INPUT + i] = lights[0].position[i];
                }
                unit_direct = forward(base, x) * lights[0].scale.rgb;
                unit_indirect = forward(base + PARAMETERS, x) * lights[0].scale.rgb;
            } else {
                float direct_sums[HIDDEN1];
                float indirect_sums[HIDDEN1];
                forward_surface(base, x, direct_sums);
                forward_surface(base + PARAMETERS, x, indirect_sums);
                for (uint l = 0u; l < constants.light_count; ++l) {
                    vec3 light = lights[l].position.xyz;
                    unit_direct += forward_lit(base, direct_sums, light) * lights[l].scale.rgb;
                    unit_indirect += forward_lit(base + PARAMETERS, indirect_sums, light) * lights[l].scale.rgb;
                }
            }
            direct += unit_direct * weight;
            indirect += unit_indirect * weight;
        }
        vec3 reflectance = surface_reflectance(id, shading);
        direct *= reflectance;
        indirect *= reflectance;
    }
    if (viewer.mirrored) {
        seen_in_mirror(viewer.fresnel, emission, direct, indirect);
    }
    imageStore(out_direct, pixel, vec4(direct, 1.0));
    imageStore(out_indirect, pixel, vec4(indirect, 1.0));
    imageStore(out_gi, pixel, vec4(emission + direct + indirect, 1.0));
}
