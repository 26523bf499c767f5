#version 450
#extension GL_GOOGLE_include_directive : require
// Mirror mask: keeps in the reflection's G-buffer only the pixels where the frame sees the
// mirror, so that the reflection's network pass shades nothing that the mirror pass would not
// use (what stands in front of the mirror, the corners of its screen rectangle). A pixel it
// drops gets object id 0: nothing there.

#include "gbuffer_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0, r32ui) uniform readonly uimage2D frame_ids;
layout(binding = 1, r32ui) uniform writeonly uimage2D seen_ids;

layout(push_constant) uniform Params {
    // The mirror's object id + 1, as the G-buffer holds it.
    uint object;
    // The first pixel dispatched.
    uvec2 origin;
} params;

void main() {
    ivec2 pixel = ivec2(params.origin + gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(frame_ids))) || id_object(imageLoad(frame_ids, pixel).x) == params.object) {
        return;
    }
    imageStore(seen_ids, pixel, uvec4(0u));
}
