// Cube shadow maps of point lights, all in one atlas image (`renderer/src/passes/shadow.rs`): light l's
// six faces side by side in row l, each SHADOW_SIZE² texels holding the distance from the
// light to the nearest surface. Face f looks along axis f / 2, towards + for even f and − for
// odd f, with a 90° frustum. shadow.vert renders with `cube_face_clip`, and the network pass
// looks up with the same function, so the two cannot disagree.
#ifndef RRF_SHADOW_CUBE_GLSL
#define RRF_SHADOW_CUBE_GLSL

// Texels per side of a face: renderer/src/passes/shadow.rs's SHADOW_SIZE.
#define SHADOW_SIZE 256
const float SHADOW_NEAR = 0.01;
const float SHADOW_FAR = 1000.0;

// Clip-space position, on face `face`, of the point at offset `d` from the light.
vec4 cube_face_clip(vec3 d, uint face) {
    uint axis = face / 2u;
    float s = (face & 1u) == 0u ? 1.0 : -1.0;
    vec3 forward = vec3(0.0);
    forward[axis] = s;
    vec3 up = axis == 1u ? vec3(0.0, 0.0, 1.0) : vec3(0.0, 1.0, 0.0);
    vec3 right = cross(forward, up);
    float z = dot(d, forward);
    float depth = SHADOW_FAR / (SHADOW_FAR - SHADOW_NEAR) * (z - SHADOW_NEAR);
    return vec4(dot(d, right), -dot(d, up), depth, z);
}

// The face whose frustum holds offset `d` from the light: that of its largest axis.
uint cube_face_of(vec3 d) {
    vec3 a = abs(d);
    uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
    return 2u * axis + (d[axis] < 0.0 ? 1u : 0u);
}

#endif
