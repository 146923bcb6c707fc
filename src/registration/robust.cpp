#include "probecomp/registration/robust.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace probecomp::registration {

const char* to_string(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::None: return "none";
    case RobustLoss::Huber: return "huber";
    case RobustLoss::Cauchy: return "cauchy";
    case RobustLoss::Trimmed: return "trimmed";
  }
  return "?";
}

double robust_weight(RobustLoss loss, double r, double scale) {
  const double z = std::abs(r) / scale;
  switch (loss) {
    case RobustLoss::None: return 1.0;
    case RobustLoss::Huber: {
      constexpr double k = 1.345;
      return z <= k ? 1.0 : k / z;
    }
    case RobustLoss::Cauchy: {
      constexpr double c = 2.3849;
      return 1.0 / (1.0 + (z / c) * (z / c));
    }
    case RobustLoss::Trimmed: return z <= kOutlierSigmas ? 1.0 : 0.0;
  }
  return 1.0;
}

}  // namespace probecomp::registration
