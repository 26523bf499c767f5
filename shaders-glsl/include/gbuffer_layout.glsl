// The packed G-buffer, 36 bytes per pixel plus depth, written by gbuffer.frag and read by the
// network passes; mirrored by renderer/src/passes/gbuffer/texel.rs (`GBufferTexel`).
//
//   surface (rgba32ui): xyz the world position's float bits, w the shading normal
//                       (octahedral, two 16-bit snorms)
//   id (r32ui):         bits 0-15 object id + 1 (0: nothing drawn), bits 16-29 material,
//                       bit 30 set where a mirror's merge step put what the mirror reflects
//                       (mirror_merge.comp), bit 31 set when the front face is seen
//                       (emitters emit from it only)
//   shading (rgba32ui): the material's textured values at the pixel, as half floats: x base
//                       colour r, g; y base colour b, emissive texture r; z emissive texture
//                       g, b; and w roughness, metallic as 16-bit unorms
//
// The emissive texture (times the light copy's scale on the moving light) multiplies the
// material's emission, in the materials buffer the network passes bind; it is 0 on a face
// that does not emit.
#ifndef RRF_GBUFFER_LAYOUT_GLSL
#define RRF_GBUFFER_LAYOUT_GLSL

vec2 sign_not_zero(vec2 v) {
    return vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0);
}

// A unit vector as two 16-bit snorms on the octahedron (Cigolle et al. 2014).
uint encode_normal(vec3 n) {
    vec2 p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if (n.z < 0.0) {
        p = (1.0 - abs(p.yx)) * sign_not_zero(p);
    }
    return packSnorm2x16(p);
}

vec3 decode_normal(uint packed) {
    vec2 p = unpackSnorm2x16(packed);
    vec3 n = vec3(p, 1.0 - abs(p.x) - abs(p.y));
    if (n.z < 0.0) {
        n.xy = (1.0 - abs(n.yx)) * sign_not_zero(n.xy);
    }
    return normalize(n);
}

uint encode_id(uint object_plus_one, uint material, bool front) {
    return (object_plus_one & 0xffffu) | ((material & 0x3fffu) << 16) | (front ? 0x80000000u : 0u);
}

const uint ID_REFLECTED = 0x40000000u;

bool id_reflected(uint id) {
    return (id & ID_REFLECTED) != 0u;
}

uint id_object(uint id) {
    return id & 0xffffu;
}

uint id_material(uint id) {
    return (id >> 16) & 0x3fffu;
}

struct Shading {
    vec3 base_color;
    vec3 emissive_texture;
    float roughness;
    float metallic;
};

uvec4 encode_shading(Shading s) {
    return uvec4(packHalf2x16(s.base_color.rg), packHalf2x16(vec2(s.base_color.b, s.emissive_texture.r)),
                 packHalf2x16(s.emissive_texture.gb), packUnorm2x16(vec2(s.roughness, s.metallic)));
}

Shading decode_shading(uvec4 packed) {
    vec2 x = unpackHalf2x16(packed.x);
    vec2 y = unpackHalf2x16(packed.y);
    vec2 z = unpackHalf2x16(packed.z);
    vec2 w = unpackUnorm2x16(packed.w);
    return Shading(vec3(x, y.x), vec3(y.y, z), w.x, w.y);
}

#endif
