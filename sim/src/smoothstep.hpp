// Quintic smoothstep shared by the motion generators (blends between key poses and motions).
#pragma once

namespace mocap::sim {

/// 0 below 0, 1 above 1, C2-continuous in between (6u^5 - 15u^4 + 10u^3).
inline double smoothstep5(double u) {
  if (u <= 0) return 0;
  if (u >= 1) return 1;
  return u * u * u * (10 - 15 * u + 6 * u * u);
}

}  // namespace mocap::sim
