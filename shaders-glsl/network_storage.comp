#version 450
#extension GL_GOOGLE_include_directive : require
// Network pass, weights in a storage buffer: per pixel, the 13 inputs from the G-buffer and
// the constants, then that object's direct and indirect networks, summed over the lights.
//
// Per object slot (object id), OBJECT_STRIDE floats: direct parameters, indirect parameters,
// input_min[13], input_max[13], direct output scale, indirect output scale, present (1 or 0).

layout(local_size_x = 8, local_size_y = 8) in;

// Whether the frame has more than one light: a pipeline of each kind, as in
// network_specialized_main.glsl.
layout(constant_id = 0) const bool SEVERAL_LIGHTS = false;

// Bindings 0-4 (G-buffer, materials, lights): network_inputs.glsl.
layout(binding = 5) readonly buffer Weights { float weights[]; };
layout(binding = 6, rgba32f) uniform writeonly image2D out_direct;
layout(binding = 7, rgba32f) uniform writeonly image2D out_indirect;
layout(binding = 8, rgba32f) uniform writeonly image2D out_gi;

layout(push_constant) uniform Constants {
    vec4 eye;
    uint light_count;
} constants;

#include "network.glsl"

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
    if (object > 0u) {
        uint base = (object - 1u) * OBJECT_STRIDE;
        uint ranges = base + 2 * PARAMETERS;
        if (weights[ranges + 2 * INPUTS + 2] > 0.5) {
            float raw[INPUTS] = raw_inputs(pixel, shading, constants.eye.xyz);
            float x[INPUTS];
            for (int i = 0; i < INPUTS; ++i) {
                x[i] = normalize_input(raw[i], weights[ranges + i], weights[ranges + INPUTS + i]);
            }
            if (!SEVERAL_LIGHTS) {
                for (int i = 0; i < 3; ++i) {
                    uint r = ranges + LIGHT_INPUT + i;
                    x[LIGHT_INPUT + i] = normalize_input(lights[0].position[i], weights[r], weights[r + INPUTS]);
                }
                direct = forward(base, x) * lights[0].scale.rgb;
                indirect = forward(base + PARAMETERS, x) * lights[0].scale.rgb;
            } else {
                float direct_sums[HIDDEN1];
                float indirect_sums[HIDDEN1];
                forward_surface(base, x, direct_sums);
                forward_surface(base + PARAMETERS, x, indirect_sums);
                for (uint l = 0u; l < constants.light_count; ++l) {
                    vec3 light;
                    for (int i = 0; i < 3; ++i) {
                        uint r = ranges + LIGHT_INPUT + i;
                        light[i] = normalize_input(lights[l].position[i], weights[r], weights[r + INPUTS]);
                    }
                    direct += forward_lit(base, direct_sums, light) * lights[l].scale.rgb;
                    indirect += forward_lit(base + PARAMETERS, indirect_sums, light) * lights[l].scale.rgb;
                }
            }
            vec3 reflectance = surface_reflectance(id, shading);
            direct *= weights[ranges + 2 * INPUTS] * reflectance;
            indirect *= weights[ranges + 2 * INPUTS + 1] * reflectance;
        }
    }
    imageStore(out_direct, pixel, vec4(direct, 1.0));
    imageStore(out_indirect, pixel, vec4(indirect, 1.0));
    imageStore(out_gi, pixel, vec4(emission + direct + indirect, 1.0));
}
