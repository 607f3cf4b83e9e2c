#pragma once
// Exact sign of the 2D orientation of three points with float coordinates. The bake builds the
// Kirkpatrick hierarchies with it and the runtime validates them at load with the same function,
// so both sides agree on every tie.

namespace drape {

// Sign of the signed area of (a, b, c): +1 counter-clockwise, -1 clockwise, 0 collinear.
// Products of two floats are exact in double; the six-term sum is evaluated exactly with
// Shewchuk's grow-expansion (round to nearest; the project compiles with -ffp-contract=off).
int Orient2dExact(float ax, float ay, float bx, float by, float cx, float cy);

}  // namespace drape
