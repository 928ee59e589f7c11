#include "core/proportion.h"

#include <algorithm>
#include <cmath>

namespace nimble {

Proportion wilson(int count, int n, double z) {
  Proportion p;
  p.count = count;
  p.n = n;
  if (n <= 0) return p;
  const double nn = n, ph = count / nn, z2 = z * z;
  const double centre = (ph + z2 / (2 * nn)) / (1 + z2 / nn);
  const double half = z / (1 + z2 / nn) * std::sqrt(ph * (1 - ph) / nn + z2 / (4 * nn * nn));
  p.p = ph;
  p.lo = std::max(0.0, centre - half);
  p.hi = std::min(1.0, centre + half);
  return p;
}

}  // namespace nimble
