/* The tractor body of cleatfmu in portable C99: a transcription of the body of
 * identification/model/tractor.py (Body.matrices: the rigid tractor with or without a pivoting
 * front axle, half tractors per side or per axle, four corners) and of the stepping scheme of
 * identification/model/stepping.py (run_body), the same operations in the same order.
 *
 * Generalized coordinates q (up to 4: heave, pitch, roll, front-axle roll of the rigid tractor; heave
 * and pitch or roll of each half; the corners' heights), diagonal masses M;
 * hub displacements from the static heights u = J q; tire forces F act through J^T:
 * M q'' = J^T (F - W).  Per communication step h, from the forces set at its start:
 *   q''_n = M^-1 J^T (F_n - W);  q'_n = q'_{n-1} + h_{n-1}/2 (q''_{n-1} + q''_n)  (not at the first step);
 *   q_{n+1} = q_n + h q'_n + h^2/2 q''_n;  predicted q'* = q'_n + h q''_n.
 * The hub outputs are z_static + J q_{n+1} and J q'*: what the tires need for the next forces.
 * The initial hub displacements and velocities are projected onto the body's motions (least squares).
 */
#ifndef CLEATFMU_BODY_H
#define CLEATFMU_BODY_H

#include "cleatfmu_names.h"

#include "cleatfmu_model.h"

#if MODEL_BODY
#define BODY_TIRES 4
#define BODY_COORDINATES 4
/* Standard gravity, m/s^2 (identification.recording.record.STANDARD_GRAVITY). */
#define BODY_GRAVITY 9.80665

/* Hub and seat outputs at `time` from the state (or the initial values before the first step) and,
 * for the accelerations, from the forces set last. */
void cleatfmu_body_outputs(double *v, double time);
/* One step of the scheme over `step` from the forces set last. */
void cleatfmu_body_step(double *v, double step);
#endif

#endif
