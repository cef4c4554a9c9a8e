#pragma once
// Implicit Euler after Baraff & Witkin (1998), "Large steps in cloth simulation", Eq. (16), the linearised
// backward Euler step
//   (M - h df/dv - h^2 df/dx) dv = h (f0 + h df/dx v0),  x1 = x0 + h (v0 + dv),
// with the spring Jacobian df_a/dx_a = -K_s, K_s = f'(l) u u^T + max(f/l, 0) (I - u u^T) (the transverse term is
// clamped at zero under compression so that the matrix stays positive definite) and df_a/dv_a = -c u u^T - gamma I.
// The CPU backend assembles the matrix for Eigen's conjugate gradient; the CUDA backend applies it matrix-free in
// its own conjugate gradient. Both take each spring's blocks from here, in double.
#include "kernels/fmpc_hd.h"
#include "kernels/spring_math.h"

namespace fmpc::kernels {

// A symmetric 3x3 block stored as xx xy xz yy yz zz.
FMPC_HD int symmetric_index(int row, int column) {
  const int r = row < column ? row : column, c = row < column ? column : row;
  return r == 0 ? c : r == 1 ? 2 + c : 5;
}

// Row r of block v, summed in column order.
FMPC_HD double symmetric_row(const double* block, int r, const double* v) {
  double sum = 0.0;
  for (int c = 0; c < 3; ++c) sum += block[symmetric_index(r, c)] * v[c];
  return sum;
}

// out = block v, each row summed in column order.
FMPC_HD void symmetric_multiply(const double* block, const double* v, double* out) {
  for (int r = 0; r < 3; ++r) out[r] = symmetric_row(block, r, v);
}

// The blocks of one spring: `stiffness` is K_s and `system` is its share h^2 K_s + h c u u^T of the system
// matrix (added to both ends' diagonal blocks and subtracted from the two off-diagonal ones). d = x_b - x_a (either
// sign gives the same blocks). A spring shorter than 1e-9 l0 has no direction: false, and both blocks are zero.
FMPC_HD bool implicit_spring_blocks(double dx, double dy, double dz, double rest, double k, double c,
                                    const SpringLawParameters<double>& law, double h, double* stiffness,
                                    double* system) {
  for (int i = 0; i < 6; ++i) stiffness[i] = system[i] = 0.0;
  const double length = square_root(dx * dx + dy * dy + dz * dz);
  if (!(length > 1e-9 * rest)) return false;
  const double u[3] = {dx / length, dy / length, dz / length};
  const double slope = spring_tension_slope(length, rest, k, law);
  const double tension_over_length = spring_tension(length, rest, k, law) / length;
  const double transverse = tension_over_length > 0.0 ? tension_over_length : 0.0;
  for (int r = 0; r < 3; ++r) {
    for (int col = r; col < 3; ++col) {
      const double uu = u[r] * u[col];
      const int i = symmetric_index(r, col);
      stiffness[i] = slope * uu + transverse * ((r == col ? 1.0 : 0.0) - uu);
      system[i] = h * h * stiffness[i] + h * c * uu;
    }
  }
  return true;
}

// A free vertex's entry on the diagonal of implicit Euler's system before the springs' and elements' blocks: its mass
// plus h times its damping per unit velocity, the nodal gamma0 + gamma1 |x - x0| and Rayleigh's alpha m (both
// backends' assembly).
FMPC_HD double implicit_vertex_diagonal(double mass, double h, double gamma0, double gamma1, double distance_from_rest,
                                        double mass_damping) {
  return mass + h * (gamma0 + gamma1 * distance_from_rest + mass_damping * mass);
}

}  // namespace fmpc::kernels
