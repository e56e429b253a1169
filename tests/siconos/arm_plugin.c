/* Siconos 4.4 plugin for the paper's two-link arm on the moving belt (docs: tests/siconos/README.md).
 *
 * The plant of docs/model.md ("Equations of motion", paper eq. 1) written as Siconos'
 * LagrangianDS  M(q) v' + F_gyr(q, v) + F_int(q, v) = p  (LagrangianDS.hpp), so
 *   M     = M(q) of docs/model.md (kg m^2)
 *   F_int = w(q, q_dot): gravity, spring, damping (N m)
 *   F_gyr = c(q, q_dot): the velocity-squared terms (N m)
 * and the contact as a LagrangianRheonomousR (LagrangianRheonomousR.hpp):
 *   h(q, t) = [z_n + H, z_t - v_belt t]  (m): the gap and the tip's position relative to the belt,
 *   G0 = dh/dq, hDot = dh/dt = [0, -v_belt] (m/s).
 * Every matrix is written column-major (Siconos' DenseMat, SiconosAlgebraTypeDef.hpp).
 *
 * The parameters (paper Table I, SI units, alpha0 in radians) come in as -D macros, so that the
 * test compiles this file with exactly the values it compares (check.py: build_plugin).
 * Signatures: PluginTypes.hpp (FPtr7 mass, FPtr6 internal forces, FPtr5 gyroscopic, FPtr4 relation).
 */
#include <math.h>

#ifndef ARM_M
#define ARM_M 0.12 /* link mass, kg */
#endif
#ifndef ARM_L
#define ARM_L 0.21 /* link length, m */
#endif
#ifndef ARM_SIGMA
#define ARM_SIGMA 0.005 /* joint damping, N m s/rad */
#endif
#ifndef ARM_K
#define ARM_K 1.3 /* lower joint's spring, N m/rad */
#endif
#ifndef ARM_H
#define ARM_H 0.3775 /* base above the belt, m */
#endif
#ifndef ARM_ALPHA0
#define ARM_ALPHA0 0.23945917337362202 /* spring rest angle, rad (13.72 deg) */
#endif
#ifndef ARM_G
#define ARM_G 9.81 /* gravity, m/s^2 */
#endif
#ifndef ARM_VBELT
#define ARM_VBELT -0.5 /* belt speed, m/s */
#endif

/* M(q), docs/model.md eq. 1 (FPtr7). */
void arm_mass(unsigned int n, double *q, double *mass, unsigned int nz, double *z)
{
  double ml2 = ARM_M * ARM_L * ARM_L, off = 0.5 * ml2 * cos(q[1] - q[0]);
  mass[0] = 4.0 / 3.0 * ml2; mass[1] = off;
  mass[2] = off;             mass[3] = ml2 / 3.0;
}

/* F_int = w(q, q_dot), docs/model.md eq. 1 (FPtr6). */
void arm_fint(double t, unsigned int n, double *q, double *v, double *f, unsigned int nz, double *z)
{
  double spring = ARM_K * (q[1] - q[0] + ARM_ALPHA0), mgl2 = 0.5 * ARM_M * ARM_G * ARM_L;
  f[0] = 3.0 * mgl2 * sin(q[0]) - spring - ARM_SIGMA * (v[1] - 2.0 * v[0]);
  f[1] = mgl2 * sin(q[1]) + spring + ARM_SIGMA * (v[1] - v[0]);
}

/* dw/dq (FPtr6, column-major). */
void arm_fint_q(double t, unsigned int n, double *q, double *v, double *jac, unsigned int nz, double *z)
{
  double mgl2 = 0.5 * ARM_M * ARM_G * ARM_L;
  jac[0] = 3.0 * mgl2 * cos(q[0]) + ARM_K; jac[1] = -ARM_K;
  jac[2] = -ARM_K;                         jac[3] = mgl2 * cos(q[1]) + ARM_K;
}

/* dw/dq_dot (FPtr6, column-major). */
void arm_fint_v(double t, unsigned int n, double *q, double *v, double *jac, unsigned int nz, double *z)
{
  jac[0] = 2.0 * ARM_SIGMA; jac[1] = -ARM_SIGMA;
  jac[2] = -ARM_SIGMA;      jac[3] = ARM_SIGMA;
}

/* F_gyr = c(q, q_dot), docs/model.md eq. 1 (FPtr5). */
void arm_fgyr(unsigned int n, double *q, double *v, double *f, unsigned int nz, double *z)
{
  double a = 0.5 * ARM_M * ARM_L * ARM_L, s = sin(q[0] - q[1]);
  f[0] = a * v[1] * v[1] * s;
  f[1] = -a * v[0] * v[0] * s;
}

/* dc/dq (FPtr5, column-major). */
void arm_fgyr_q(unsigned int n, double *q, double *v, double *jac, unsigned int nz, double *z)
{
  double a = 0.5 * ARM_M * ARM_L * ARM_L, c = cos(q[0] - q[1]);
  jac[0] = a * v[1] * v[1] * c;  jac[1] = -a * v[0] * v[0] * c;
  jac[2] = -a * v[1] * v[1] * c; jac[3] = a * v[0] * v[0] * c;
}

/* dc/dq_dot (FPtr5, column-major). */
void arm_fgyr_v(unsigned int n, double *q, double *v, double *jac, unsigned int nz, double *z)
{
  double a = 0.5 * ARM_M * ARM_L * ARM_L, s = sin(q[0] - q[1]);
  jac[0] = 0.0;               jac[1] = -2.0 * a * v[0] * s;
  jac[2] = 2.0 * a * v[1] * s; jac[3] = 0.0;
}

/* h(q, t) = [z_n + H, z_t - v_belt t] (FPtr4), docs/model.md "Geometry and state". */
void arm_h(unsigned int n, double *q, double t, unsigned int ny, double *y, unsigned int nz, double *z)
{
  y[0] = -ARM_L * (cos(q[0]) + cos(q[1])) + ARM_H;
  y[1] = ARM_L * (sin(q[0]) + sin(q[1])) - ARM_VBELT * t;
}

/* G0 = dh/dq = [j2^T; j1^T] (FPtr4, 2x2 column-major), docs/model.md's J with its rows swapped. */
void arm_g0(unsigned int n, double *q, double t, unsigned int ny, double *g, unsigned int nz, double *z)
{
  g[0] = ARM_L * sin(q[0]); g[1] = ARM_L * cos(q[0]);
  g[2] = ARM_L * sin(q[1]); g[3] = ARM_L * cos(q[1]);
}

/* hDot = dh/dt = [0, -v_belt] (FPtr4): the slip is z_t_dot - v_belt, docs/model.md's z_r_dot. */
void arm_hdot(unsigned int n, double *q, double t, unsigned int ny, double *hd, unsigned int nz, double *z)
{
  hd[0] = 0.0;
  hd[1] = -ARM_VBELT;
}
