// The network units: the parts of objects that each have one direct and one indirect network
// (the whole object, or where a leaf of its direct kd-tree meets one of its indirect tree;
// baker/src/partition.rs). renderer/src/passes/network/units.rs (`unit_table`) writes the
// table: per object (id - 1) the index of its first unit and how many it has (0: no
// networks), then per unit UNIT_BLEND floats: the blend boxes of its direct and its indirect
// leaf.
//
// Leaves blend across their cuts: a unit's weight at a point is its direct leaf's weight
// times its indirect leaf's, and an object's units' weights sum to one, so that the pixel's
// radiance is the weighted sum of the units whose weight is not 0 there (one, away from the
// cuts).
//
// Before including: UNITS_BINDING.
#ifndef RRF_NETWORK_UNITS_GLSL
#define RRF_NETWORK_UNITS_GLSL

#include "network_layout.glsl"

layout(std430, binding = UNITS_BINDING) readonly buffer Units { float units[]; };

// The weights are `precise` (no fused or reordered arithmetic): every unit's pipeline
// computes the weights of the others at its pixels to know whether it adds to them or
// finishes the sum, and must get exactly what each computes for itself, however the driver
// compiles the code around it.

// 0 below the band at ± band, 1 above it, a smoothstep across it; without a band, the step
// x >= at. The twin of `rising` in baker/src/partition.rs.
float rising(float x, float at, float band) {
    if (band > 0.0) {
        precise float t = clamp((x - (at - band)) / (2.0 * band), 0.0, 1.0);
        precise float s = t * t * (3.0 - 2.0 * t);
        return s;
    }
    return x >= at ? 1.0 : 0.0;
}

// The weight at `p` of the leaf whose blend box starts at units[b]: the twin of
// `BlendBox::weight` in baker/src/partition.rs.
float leaf_weight(uint b, vec3 p) {
    precise float w = 1.0;
    for (uint a = 0u; a < 3u; ++a) {
        precise float low = rising(p[a], units[b + a], units[b + 6u + a]);
        precise float high = 1.0 - rising(p[a], units[b + 3u + a], units[b + 9u + a]);
        w *= low * high;
    }
    return w;
}

// Unit `u`'s weight at `p`, in a table of `objects` object entries.
float unit_weight(uint objects, uint u, vec3 p) {
    uint b = 2u * objects + u * UNIT_BLEND;
    precise float w = leaf_weight(b, p) * leaf_weight(b + UNIT_BLEND / 2u, p);
    return w;
}

// The first unit of object (id - 1) `object`, and how many it has.
uvec2 object_units(uint object) {
    return uvec2(units[2u * object], units[2u * object + 1u]);
}

#endif
