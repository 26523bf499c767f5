#ifndef RRF_NETWORK_CLASSIFY_MAIN_GLSL
#define RRF_NETWORK_CLASSIFY_MAIN_GLSL
// Network pass, step 1 of the specialized variants: sorts the image's 8×8 tiles by object.
//
// Each workgroup is one tile. It appends the tile to the list of every object with networks
// that covers one of its pixels, counting in that object's indirect dispatch arguments, so
// that each object's pipeline then runs only over its own tiles. Pixels that no network
// covers (background, objects without networks) get their final values here: with DISPLAY
// defined (network_classify_display.comp; network_classify.comp writes the three radiance images) in the one tonemapped display image.

layout(local_size_x = 8, local_size_y = 8) in;

// Object ids the tile list can tell apart; the host checks a scene against it.
#define MAX_OBJECTS 1024

#include "gbuffer_layout.glsl"

layout(binding = 0, r32ui) uniform readonly uimage2D gbuffer_id;
// Per material: rgb emitted radiance (before the emissive texture), w specular factor.
layout(std430, binding = 1) readonly buffer Materials { vec4 materials[]; };
layout(binding = 2, rgba32ui) uniform readonly uimage2D gbuffer_shading;
// 1 where object (id - 1) has networks.
layout(binding = 3) readonly buffer Trained { uint trained[]; };
// VkDispatchIndirectCommand per object: x counts its tiles; y and z are 1.
layout(binding = 4) buffer Dispatch { uint dispatch[]; };
// Object (id - 1)'s tiles from index (id - 1) * tile_capacity, each as x | y << 16.
layout(binding = 5) writeonly buffer Tiles { uint tiles[]; };
#ifdef DISPLAY
layout(binding = 6, rgba8) uniform writeonly image2D display;
#include "tonemap.glsl"
#else
layout(binding = 6, rgba32f) uniform writeonly image2D out_direct;
layout(binding = 7, rgba32f) uniform writeonly image2D out_indirect;
layout(binding = 8, rgba32f) uniform writeonly image2D out_gi;
#endif

layout(push_constant) uniform Constants {
    uint objects;
    uint tile_capacity;
    // DISPLAY only: 2^EV, and the component shown (0 global, 1 direct, 2 indirect).
    float exposure_scale;
    uint shown;
} constants;

shared uint seen[MAX_OBJECTS / 32];

void main() {
    uint lane = gl_LocalInvocationIndex;
    for (uint word = lane; word < MAX_OBJECTS / 32; word += 64u) {
        seen[word] = 0u;
    }
    barrier();

    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(pixel, imageSize(gbuffer_id)))) {
        uint packed = imageLoad(gbuffer_id, pixel).r;
        uint id = id_object(packed);
        if (id > 0u && trained[id - 1u] != 0u) {
            atomicOr(seen[(id - 1u) / 32u], 1u << ((id - 1u) % 32u));
        } else {
            vec3 emission = vec3(0.0);
            if (id > 0u) {
                Shading shading = decode_shading(imageLoad(gbuffer_shading, pixel));
                emission = materials[id_material(packed)].rgb * shading.emissive_texture;
            }
#ifdef DISPLAY
            vec3 emitted = constants.shown == 0u ? emission : vec3(0.0);
            imageStore(display, pixel, vec4(tonemap(emitted, constants.exposure_scale), 1.0));
#else
            imageStore(out_direct, pixel, vec4(0.0, 0.0, 0.0, 1.0));
            imageStore(out_indirect, pixel, vec4(0.0, 0.0, 0.0, 1.0));
            imageStore(out_gi, pixel, vec4(emission, 1.0));
#endif
        }
    }
    barrier();

    uint tile = gl_WorkGroupID.x | (gl_WorkGroupID.y << 16);
    for (uint object = lane; object < constants.objects; object += 64u) {
        if ((seen[object / 32u] & (1u << (object % 32u))) != 0u) {
            uint slot = atomicAdd(dispatch[3u * object], 1u);
            tiles[object * constants.tile_capacity + slot] = tile;
        }
    }
}

#endif
