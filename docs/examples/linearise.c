/* A one-step linearised model of the arm for a model-predictive controller, from the C that
 * `equations --what qdd,dqdd` writes: x = (q, qd), u = tau, x' = (qd, qdd(q, qd, tau)),
 * stepped by explicit Euler over dt and linearised at a state:
 *     x[k+1] ~ x[k] + dt f(x[k], u[k]) + A dx + B du,
 *     A = dt [[0, I], [dqdd/dq, dqdd/dqd]] + I,   B = dt [[0], [M^-1]].
 * The prediction is checked against the nonlinear step at a nearby state and input. */
#include <math.h>
#include <stdio.h>

#include "irb140_eom.h"

#define N IRB140_N

static void step(const double x[2 * N], const double u[N], double dt, double next[2 * N])
{
    double qdd[N];
    irb140_qdd(x, x + N, u, qdd);
    for (int i = 0; i < N; ++i) {
        next[i] = x[i] + dt * x[N + i];
        next[N + i] = x[N + i] + dt * qdd[i];
    }
}

int main(void)
{
    const double dt = 0.002; /* s */
    double x[2 * N] = {0.3, -1.0, 0.8, 0.2, 0.5, -0.4, 0.5, -0.2, 0.3, 1.0, -0.6, 0.8};
    double u[N] = {5.0, 250.0, 80.0, 5.0, 8.0, 5.0}; /* N m */
    double dqdd_dq[N * N], dqdd_dqd[N * N], Minv[N * N];
    double A[2 * N][2 * N] = {{0.0}}, B[2 * N][N] = {{0.0}};

    irb140_dqdd(x, x + N, u, dqdd_dq, dqdd_dqd);
    irb140_Minv(x, Minv);
    for (int i = 0; i < 2 * N; ++i) A[i][i] = 1.0;
    for (int i = 0; i < N; ++i) {
        A[i][N + i] += dt;
        for (int j = 0; j < N; ++j) {
            A[N + i][j] += dt * dqdd_dq[i * N + j];
            A[N + i][N + j] += dt * dqdd_dqd[i * N + j];
            B[N + i][j] = dt * Minv[i * N + j];
        }
    }

    double dx[2 * N], du[N], x_near[2 * N], u_near[N], base[2 * N], near[2 * N];
    for (int i = 0; i < 2 * N; ++i) dx[i] = i < N ? 1e-4 : 1e-3;
    for (int i = 0; i < N; ++i) du[i] = 0.1;
    for (int i = 0; i < 2 * N; ++i) x_near[i] = x[i] + dx[i];
    for (int i = 0; i < N; ++i) u_near[i] = u[i] + du[i];
    step(x, u, dt, base);
    step(x_near, u_near, dt, near);
    double error = 0.0, change = 0.0;
    for (int i = 0; i < 2 * N; ++i) {
        double predicted = base[i] - x[i]; /* the linear model's change of the step */
        for (int j = 0; j < 2 * N; ++j) predicted += A[i][j] * dx[j];
        for (int j = 0; j < N; ++j) predicted += B[i][j] * du[j];
        error = fmax(error, fabs(near[i] - x[i] - predicted));
        change = fmax(change, fabs(near[i] - base[i]));
    }
    printf("one step of %g s: the state moves by %.1e, the linear model is off by %.1e\n", dt, change, error);
    return error < 1e-4 * change ? 0 : 1;
}
