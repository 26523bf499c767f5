// Radiance regression function on the GPU: INPUTS → HIDDEN1 tanh → HIDDEN2 tanh → 3, reading
// the parameters from `weights` at `base`, with the input normalisation and the output scale
// folded in (renderer/src/passes/network/weights.rs, `fold`), so that it takes raw inputs.
// Follows baker/src/network.rs (`Network::evaluate`, `forward`), with the first layer split
// in two so that several lights share its per-pixel part; the shape and parameter offsets come
// from baker/src/network_layout.rs (through network_inputs.glsl).
#ifndef RRF_NETWORK_GLSL
#define RRF_NETWORK_GLSL

#include "network_inputs.glsl"

// The network after its first layer's sums `s` (bias plus weighted inputs).
vec3 forward_from_sums(uint base, float s[HIDDEN1]) {
    float h1[HIDDEN1];
    for (int j = 0; j < HIDDEN1; ++j) {
        h1[j] = network_tanh(s[j]);
    }
    float h2[HIDDEN2];
    for (int k = 0; k < HIDDEN2; ++k) {
        float sum = weights[base + B2 + k];
        for (int j = 0; j < HIDDEN1; ++j) {
            sum += weights[base + W2 + k * HIDDEN1 + j] * h1[j];
        }
        h2[k] = network_tanh(sum);
    }
    vec3 y;
    for (int c = 0; c < 3; ++c) {
        float sum = weights[base + B3 + c];
        for (int k = 0; k < HIDDEN2; ++k) {
            sum += weights[base + W3 + c * HIDDEN2 + k] * h2[k];
        }
        y[c] = sum;
    }
    return y;
}

// The network on raw inputs `x` (one light).
vec3 forward(uint base, float x[INPUTS]) {
    float s[HIDDEN1];
    for (int j = 0; j < HIDDEN1; ++j) {
        float sum = weights[base + B1 + j];
        for (int i = 0; i < INPUTS; ++i) {
            sum += weights[base + W1 + j * INPUTS + i] * x[i];
        }
        s[j] = sum;
    }
    return forward_from_sums(base, s);
}

// For several lights. First layer, part 1: the bias plus the weighted inputs other than the
// light position (raw `x`), once per pixel; `forward_lit` adds the light's share once
// per light.
void forward_surface(uint base, float x[INPUTS], out float s[HIDDEN1]) {
    for (int j = 0; j < HIDDEN1; ++j) {
        float sum = weights[base + B1 + j];
        for (int i = 0; i < INPUTS; ++i) {
            if (i < LIGHT_INPUT || i >= LIGHT_INPUT + 3) {
                sum += weights[base + W1 + j * INPUTS + i] * x[i];
            }
        }
        s[j] = sum;
    }
}

// The network on first-layer sums `s` and the light position `light`.
vec3 forward_lit(uint base, float s[HIDDEN1], vec3 light) {
    float lit[HIDDEN1];
    for (int j = 0; j < HIDDEN1; ++j) {
        lit[j] = s[j];
        for (int i = 0; i < 3; ++i) {
            lit[j] += weights[base + W1 + j * INPUTS + LIGHT_INPUT + i] * light[i];
        }
    }
    return forward_from_sums(base, lit);
}

#endif
