#version 450
#extension GL_GOOGLE_include_directive : require
// Network pass, weights in a storage buffer: per pixel, the 13 inputs from the G-buffer and
// the constants, then that object's direct and indirect networks.
//
// Per object slot (object id), OBJECT_STRIDE floats: direct parameters, indirect parameters,
// input_min[13], input_max[13], direct output scale, indirect output scale, present (1 or 0).

layout(local_size_x = 8, local_size_y = 8) in;

// Bindings 0-3 (G-buffer, materials): network_inputs.glsl.
layout(binding = 4) readonly buffer Weights { float weights[]; };
layout(binding = 5, rgba32f) uniform writeonly image2D out_direct;
layout(binding = 6, rgba32f) uniform writeonly image2D out_indirect;
layout(binding = 7, rgba32f) uniform writeonly image2D out_gi;

layout(push_constant) uniform Constants {
    vec4 eye;
    vec4 light;
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
            float raw[INPUTS] = raw_inputs(pixel, shading, constants.eye.xyz, constants.light.xyz);
            float x[INPUTS];
            for (int i = 0; i < INPUTS; ++i) {
                x[i] = normalize_input(raw[i], weights[ranges + i], weights[ranges + INPUTS + i]);
            }
            vec3 reflectance = surface_reflectance(id, shading);
            direct = forward(base, x) * weights[ranges + 2 * INPUTS] * reflectance;
            indirect = forward(base + PARAMETERS, x) * weights[ranges + 2 * INPUTS + 1] * reflectance;
        }
    }
    imageStore(out_direct, pixel, vec4(direct, 1.0));
    imageStore(out_indirect, pixel, vec4(indirect, 1.0));
    imageStore(out_gi, pixel, vec4(emission + direct + indirect, 1.0));
}
