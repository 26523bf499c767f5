// The network units: the parts of objects that each have one direct and one indirect network
// (the whole object, or where a leaf of its direct kd-tree meets one of its indirect tree;
// baker/src/partition.rs). network_pass.rs (`unit_table`) writes the table: per object (id - 1)
// the index of its first unit and how many it has (0: no networks), then per unit its box,
// min xyz then max xyz, half-open. An object's boxes partition space, so each of its pixels
// is in exactly one.
//
// Before including: UNITS_BINDING, and a push-constant block `constants` with `objects`, the
// number of object ids.
#ifndef RRF_NETWORK_UNITS_GLSL
#define RRF_NETWORK_UNITS_GLSL

#include "network_layout.glsl"

layout(std430, binding = UNITS_BINDING) readonly buffer Units { float units[]; };

// The unit of object (id - 1) `object` that holds position `p`, or -1 if the object has no
// networks.
int find_unit(uint object, vec3 p) {
    uint first = uint(units[2u * object]);
    uint count = uint(units[2u * object + 1u]);
    uint boxes = 2u * constants.objects;
    for (uint u = first; u < first + count; ++u) {
        uint b = boxes + u * UNIT_BOX;
        vec3 lo = vec3(units[b], units[b + 1u], units[b + 2u]);
        vec3 hi = vec3(units[b + 3u], units[b + 4u], units[b + 5u]);
        if (all(greaterThanEqual(p, lo)) && all(lessThan(p, hi))) {
            return int(u);
        }
    }
    return -1;
}

#endif
