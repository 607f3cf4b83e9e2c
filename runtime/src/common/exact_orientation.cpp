#include "drape/runtime/exact_orientation.h"

namespace drape {
namespace {

void TwoSum(double a, double b, double* s, double* e) {
  *s = a + b;
  const double bb = *s - a;
  *e = (a - (*s - bb)) + (b - bb);
}

int SignOfExactSum(const double* terms, int count) {
  double expansion[16];
  int size = 0;
  for (int t = 0; t < count; ++t) {
    double q = terms[t];
    int kept = 0;
    for (int i = 0; i < size; ++i) {
      double s, e;
      TwoSum(q, expansion[i], &s, &e);
      if (e != 0.0) expansion[kept++] = e;
      q = s;
    }
    expansion[kept++] = q;
    size = kept;
  }
  for (int i = size - 1; i >= 0; --i)
    if (expansion[i] != 0.0) return expansion[i] > 0.0 ? 1 : -1;
  return 0;
}

}  // namespace

int Orient2dExact(float ax, float ay, float bx, float by, float cx, float cy) {
  // Shewchuk's filter (orient2d, stage A): the double determinant's sign is certain when it
  // exceeds its rounding bound (3 + 16 eps) eps (|left| + |right|), eps = 2^-53. Float inputs are
  // exact in double and their products cannot underflow, so the bound holds for every input; the
  // exact sum below decides only near-collinear points (most of a Kirkpatrick build's tests are
  // far from it: the filter answers them at a fraction of the cost).
  const double left = (double(ax) - cx) * (double(by) - cy);
  const double right = (double(ay) - cy) * (double(bx) - cx);
  const double det = left - right;
  double sum;
  // The products' signs are exact (rounding keeps a sign and 0 is exact): opposite signs decide.
  if (left > 0.0) {
    if (right <= 0.0) return 1;
    sum = left + right;
  } else if (left < 0.0) {
    if (right >= 0.0) return -1;
    sum = -left - right;
  } else {  // left is exactly 0 (a difference is): the sign is right's, negated
    return right > 0.0 ? -1 : (right < 0.0 ? 1 : 0);
  }
  constexpr double kEpsilon = 1.1102230246251565e-16;  // 2^-53
  constexpr double kBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
  if (det >= kBound * sum || -det >= kBound * sum) return det > 0.0 ? 1 : -1;
  const double terms[6] = {double(bx) * cy,  -double(bx) * ay, -double(ax) * cy,
                           -double(by) * cx, double(by) * ax,  double(ay) * cx};
  return SignOfExactSum(terms, 6);
}

}  // namespace drape
