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
  const double terms[6] = {double(bx) * cy,  -double(bx) * ay, -double(ax) * cy,
                           -double(by) * cx, double(by) * ax,  double(ay) * cx};
  return SignOfExactSum(terms, 6);
}

}  // namespace drape
