#pragma once
// Standard normal deviates by the ziggurat method (Marsaglia and Tsang, "The ziggurat method
// for generating random variables", J. Stat. Softw. 5(8), 2000), 128 layers: 98.8 % of deviates
// cost one 64-bit draw, a multiplication and a table look-up, where SimRng::normal (Box-Muller)
// costs a logarithm, a square root and a sine/cosine pair per two. The depth error model draws
// one deviate per pixel (217 k per frame), which made Box-Muller its largest cost.
//
// The half-normal density f(x) = exp(-x^2 / 2) is covered by 128 layers of equal area v: layer
// 0 is the rectangle [0, r] x [0, f(r)] plus the tail beyond r (r = 3.4426...), layer i >= 1
// the rectangle [0, x_i] x [f(x_i), f(x_{i+1})], with x_1 = r and x_128 = 0. A draw picks a
// layer i and a point x = u x_i; x < x_{i+1} lies under the curve for sure; otherwise the
// tail (i = 0, Marsaglia's exponential method) or a test against f decides.
#include "sim/sim_rng.hpp"

namespace posefuse::sim {

// Deterministic for the rng's stream, like SimRng::normal (tables from the same libm).
double ziggurat_normal(SimRng& rng);

}  // namespace posefuse::sim
