// What every network variant shares: the network's shape, its activation, and the 13 raw
// inputs of a pixel, in the order of `raw_inputs` in baker/src/network.rs.
#ifndef RRF_NETWORK_INPUTS_GLSL
#define RRF_NETWORK_INPUTS_GLSL

#define INPUTS 13
#define HIDDEN1 20
#define HIDDEN2 10

float network_tanh(float x) {
    return tanh(x);
}

// Position, direction towards the eye, light position, shading normal, roughness.
float[INPUTS] raw_inputs(vec4 position_roughness, vec3 normal, vec3 eye, vec3 light) {
    vec3 p = position_roughness.xyz;
    vec3 v = normalize(eye - p);
    return float[INPUTS](p.x, p.y, p.z, v.x, v.y, v.z, light.x, light.y, light.z, normal.x, normal.y, normal.z,
                         position_roughness.w);
}

#endif
