#ifndef RRF_NETWORK_CLASSIFY_MAIN_GLSL
#define RRF_NETWORK_CLASSIFY_MAIN_GLSL
// Network pass, step 1 of the specialized variants: sorts the image's 8×8 tiles by network
// unit (network_units.glsl).
//
// Each workgroup is one tile. It appends the tile to the list of every unit whose weight is
// not 0 at one of its pixels (one per pixel, or several where leaves blend), counting in
// that unit's indirect dispatch arguments, so that each unit's pipeline then runs only over
// its own tiles. Pixels that no network covers (background, objects without networks, as
// seen directly or in a mirror) get their final values here: the three radiance images
// (network_classify.comp), or with DISPLAY defined (network_classify_display.comp) the one
// tonemapped display image.

layout(local_size_x = 8, local_size_y = 8) in;

// Units the tile list can tell apart; the host checks a model against it.
#define MAX_UNITS 1024

#include "gbuffer_layout.glsl"
#include "network_interface.glsl"
#include "mirror_weights.glsl"

layout(binding = SURFACE_BINDING, rgba32ui) uniform readonly uimage2D gbuffer_surface;
layout(binding = ID_BINDING, r32ui) uniform readonly uimage2D gbuffer_id;
// Per material: rgb emitted radiance (before the emissive texture), w specular factor.
layout(std430, binding = MATERIALS_BINDING) readonly buffer Materials { vec4 materials[]; };
layout(binding = SHADING_BINDING, rgba32ui) uniform readonly uimage2D gbuffer_shading;
// VkDispatchIndirectCommand per unit: x counts its tiles; y and z are 1.
layout(binding = DISPATCH_BINDING) buffer Dispatch { uint dispatch[]; };
// Unit u's tiles from index u * tile_capacity, each as x | y << 16.
layout(binding = TILES_BINDING) writeonly buffer Tiles { uint tiles[]; };
#ifdef DISPLAY
layout(binding = FIRST_OUTPUT_BINDING, rgba8) uniform writeonly image2D display;
#include "tonemap.glsl"
#define OUTPUT_IMAGES 1
#else
layout(binding = FIRST_OUTPUT_BINDING, rgba32f) uniform writeonly image2D out_direct;
layout(binding = FIRST_OUTPUT_BINDING + 1, rgba32f) uniform writeonly image2D out_indirect;
layout(binding = FIRST_OUTPUT_BINDING + 2, rgba32f) uniform writeonly image2D out_gi;
#define OUTPUT_IMAGES 3
#endif

layout(push_constant) uniform Constants {
    uint objects;
    uint units;
    uint tile_capacity;
    // DISPLAY only: 2^EV, and the component shown (0 global, 1 direct, 2 indirect).
    float exposure_scale;
    uint shown;
} constants;

// The unit table, after the images (network_units.glsl).
#define UNITS_BINDING (FIRST_OUTPUT_BINDING + OUTPUT_IMAGES)
#include "network_units.glsl"

shared uint seen[MAX_UNITS / 32];

void main() {
    uint lane = gl_LocalInvocationIndex;
    for (uint word = lane; word < MAX_UNITS / 32; word += 64u) {
        seen[word] = 0u;
    }
    barrier();

    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (all(lessThan(pixel, imageSize(gbuffer_id)))) {
        uint packed = imageLoad(gbuffer_id, pixel).r;
        uint id = id_object(packed);
        uvec2 range = id > 0u ? object_units(id - 1u) : uvec2(0u);
        if (range.y > 0u) {
            vec3 p = uintBitsToFloat(imageLoad(gbuffer_surface, pixel).xyz);
            for (uint unit = range.x; unit < range.x + range.y; ++unit) {
                if (unit_weight(constants.objects, unit, p) > 0.0) {
                    atomicOr(seen[unit / 32u], 1u << (unit % 32u));
                }
            }
        } else {
            vec3 emission = vec3(0.0);
            if (id > 0u) {
                Shading shading = decode_shading(imageLoad(gbuffer_shading, pixel));
                emission = materials[id_material(packed)].rgb * shading.emissive_texture;
            }
            vec3 direct = vec3(0.0);
            vec3 indirect = vec3(0.0);
            if (id_reflected(packed)) {
                seen_in_mirror(imageLoad(mirror_weights, pixel).rgb, emission, direct, indirect);
            }
#ifdef DISPLAY
            vec3 shown = constants.shown == 0u ? emission + direct : constants.shown == 1u ? direct : vec3(0.0);
            imageStore(display, pixel, vec4(tonemap(shown, constants.exposure_scale), 1.0));
#else
            imageStore(out_direct, pixel, vec4(direct, 1.0));
            imageStore(out_indirect, pixel, vec4(indirect, 1.0));
            imageStore(out_gi, pixel, vec4(emission + direct, 1.0));
#endif
        }
    }
    barrier();

    uint tile = gl_WorkGroupID.x | (gl_WorkGroupID.y << 16);
    for (uint unit = lane; unit < constants.units; unit += 64u) {
        if ((seen[unit / 32u] & (1u << (unit % 32u))) != 0u) {
            uint slot = atomicAdd(dispatch[3u * unit], 1u);
            tiles[unit * constants.tile_capacity + slot] = tile;
        }
    }
}

#endif
