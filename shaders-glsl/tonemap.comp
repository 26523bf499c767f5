#version 450
#extension GL_GOOGLE_include_directive : require
// Tonemap pass: linear HDR (rgba32f) in, display sRGB (rgba8) out.

#include "tonemap.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0, rgba32f) uniform readonly image2D hdr;
layout(binding = 1, rgba8) uniform writeonly image2D ldr;

layout(push_constant) uniform Params {
    float exposure_scale;
} params;

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(ldr)))) {
        return;
    }
    vec3 radiance = imageLoad(hdr, pixel).rgb;
    imageStore(ldr, pixel, vec4(tonemap(radiance, params.exposure_scale), 1.0));
}
