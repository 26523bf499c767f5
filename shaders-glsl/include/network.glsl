// Radiance regression function on the GPU: INPUTS → HIDDEN1 tanh → HIDDEN2 tanh → 3, reading
// the parameters from `weights` at `base`. Follows baker/src/network.rs (`Network::evaluate`,
// `forward`) line for line; the shape and parameter offsets come from
// baker/src/network_layout.rs (through network_inputs.glsl).
#ifndef RRF_NETWORK_GLSL
#define RRF_NETWORK_GLSL

#include "network_inputs.glsl"

// Maps x from [lo, hi] to [-1, 1]; a constant input maps to 0.
float normalize_input(float x, float lo, float hi) {
    float range = hi - lo;
    return range > 1e-6 ? 2.0 * (x - lo) / range - 1.0 : 0.0;
}

// The network on normalised inputs `x`.
vec3 forward(uint base, float x[INPUTS]) {
    float h1[HIDDEN1];
    for (int j = 0; j < HIDDEN1; ++j) {
        float s = weights[base + B1 + j];
        for (int i = 0; i < INPUTS; ++i) {
            s += weights[base + W1 + j * INPUTS + i] * x[i];
        }
        h1[j] = network_tanh(s);
    }
    float h2[HIDDEN2];
    for (int k = 0; k < HIDDEN2; ++k) {
        float s = weights[base + B2 + k];
        for (int j = 0; j < HIDDEN1; ++j) {
            s += weights[base + W2 + k * HIDDEN1 + j] * h1[j];
        }
        h2[k] = network_tanh(s);
    }
    vec3 y;
    for (int c = 0; c < 3; ++c) {
        float s = weights[base + B3 + c];
        for (int k = 0; k < HIDDEN2; ++k) {
            s += weights[base + W3 + c * HIDDEN2 + k] * h2[k];
        }
        y[c] = s;
    }
    return y;
}

#endif
