/* The rigid tractor body (see cleatfmu_body.h). */
#include <math.h>
#include <string.h>

#include "cleatfmu_body.h"

#if MODEL_BODY

typedef struct {
    int nq;                                   /* number of coordinates (3 for the rigid tractor, else 4) */
    double J[BODY_TIRES][BODY_COORDINATES];   /* hub displacement per coordinate; unused columns 0 */
    double minv[BODY_COORDINATES];            /* 1 / generalized mass; 1 for unused coordinates */
    double seat[BODY_COORDINATES];            /* seat displacement per coordinate */
} BodyMatrices;

static const double side[BODY_TIRES] = {1.0, -1.0, 1.0, -1.0};   /* FL, FR, RL, RR: + left */
static const int front[BODY_TIRES] = {1, 1, 0, 0};

/* A pair of tires (t0, t1) as one body with coordinates 2g (heave) and 2g + 1: pitch (a side, t0 front)
 * or roll scaled by the half-track (an axle, t0 left). */
static void pair(const double *v, BodyMatrices *b, int g, int t0, int t1, int pitch) {
    double w0 = v[VR_LOAD_FL + t0], w1 = v[VR_LOAD_FL + t1], m = (w0 + w1) / BODY_GRAVITY;
    b->J[t0][2 * g] = b->J[t1][2 * g] = 1.0;
    b->minv[2 * g] = 1.0 / m;
    if (pitch) {
        double a = v[VR_WHEELBASE] * w1 / (w0 + w1), bb = v[VR_WHEELBASE] - a;
        b->J[t0][2 * g + 1] = a;
        b->J[t1][2 * g + 1] = -bb;
        b->minv[2 * g + 1] = 1.0 / (v[VR_PITCH_INDEX] * m * a * bb);
    } else {
        double ybar = (w0 - w1) / (w0 + w1);
        b->J[t0][2 * g + 1] = 1.0 - ybar;
        b->J[t1][2 * g + 1] = -1.0 - ybar;
        b->minv[2 * g + 1] = 1.0 / (v[VR_ROLL_INDEX] * m);
    }
}

/* J, 1/M (Body._matrices of identification.model.tractor, every kind) and the seat row: the whole tractor's
 * (comfort.ride.seat_row), otherwise the hubs' displacements interpolated bilinearly at the seat. */
static void matrices(const double *v, BodyMatrices *b) {
    int pitch = v[VR_PITCH_COUPLING] != 0.0, roll = v[VR_ROLL_COUPLING] != 0.0;
    int pivot = pitch && roll && v[VR_FRONT_AXLE_PIVOT] != 0.0, i, j;
    memset(b, 0, sizeof *b);
    for (j = 0; j < BODY_COORDINATES; j++) b->minv[j] = 1.0;
    if (pitch && roll) {
        double W[BODY_TIRES], total = 0.0, rear = 0.0, front_load = 0.0, sw = 0.0, a, bb, ybar, mass;
        for (i = 0; i < BODY_TIRES; i++) W[i] = v[VR_LOAD_FL + i];
        for (i = 0; i < BODY_TIRES; i++) total += W[i];
        for (i = 0; i < BODY_TIRES; i++) if (!front[i]) rear += W[i];
        for (i = 0; i < BODY_TIRES; i++) if (front[i]) front_load += W[i];
        for (i = 0; i < BODY_TIRES; i++) sw += side[i] * W[i];
        a = v[VR_WHEELBASE] * rear / total;
        bb = v[VR_WHEELBASE] - a;
        ybar = sw / total;
        mass = total / BODY_GRAVITY;
        for (i = 0; i < BODY_TIRES; i++) {
            b->J[i][0] = 1.0;
            b->J[i][1] = front[i] ? a : -bb;
            b->J[i][2] = pivot && front[i] ? -ybar : side[i] - ybar;
            b->J[i][3] = pivot && front[i] ? side[i] : 0.0;
        }
        b->minv[0] = 1.0 / mass;
        b->minv[1] = 1.0 / (v[VR_PITCH_INDEX] * mass * a * bb);
        b->minv[2] = 1.0 / (v[VR_ROLL_INDEX] * mass);
        if (pivot) b->minv[3] = 1.0 / (v[VR_PIVOT_INDEX] * front_load / BODY_GRAVITY);
        b->nq = pivot ? 4 : 3;
        b->seat[0] = 1.0;
        b->seat[1] = a - v[VR_SEAT_X];
        b->seat[2] = v[VR_SEAT_Y] - ybar;
        return;
    }
    b->nq = 4;
    if (pitch) {                 /* sides: (FL, RL), (FR, RR) */
        pair(v, b, 0, 0, 2, 1);
        pair(v, b, 1, 1, 3, 1);
    } else if (roll) {           /* axles: (FL, FR), (RL, RR) */
        pair(v, b, 0, 0, 1, 0);
        pair(v, b, 1, 2, 3, 0);
    } else {                     /* four corners */
        for (i = 0; i < BODY_TIRES; i++) {
            b->J[i][i] = 1.0;
            b->minv[i] = 1.0 / (v[VR_LOAD_FL + i] / BODY_GRAVITY);
        }
    }
    {
        double xi = v[VR_SEAT_X] / v[VR_WHEELBASE], eta = v[VR_SEAT_Y], w[BODY_TIRES];
        w[0] = (1.0 - xi) * 0.5 * (1.0 + eta);
        w[1] = (1.0 - xi) * 0.5 * (1.0 - eta);
        w[2] = xi * 0.5 * (1.0 + eta);
        w[3] = xi * 0.5 * (1.0 - eta);
        for (j = 0; j < BODY_COORDINATES; j++)
            for (i = 0; i < BODY_TIRES; i++) b->seat[j] += w[i] * b->J[i][j];
    }
}

/* Least-squares coordinates x (nq) of hub values u: (J^T J) x = J^T u, Gaussian elimination with pivoting. */
static void project(const BodyMatrices *b, const double *u, double *x) {
    double A[BODY_COORDINATES][BODY_COORDINATES + 1];
    int n = b->nq, i, j, k, t;
    for (i = 0; i < BODY_COORDINATES; i++) x[i] = 0.0;
    for (i = 0; i < n; i++) {
        for (j = 0; j < n; j++) {
            A[i][j] = 0.0;
            for (t = 0; t < BODY_TIRES; t++) A[i][j] += b->J[t][i] * b->J[t][j];
        }
        A[i][n] = 0.0;
        for (t = 0; t < BODY_TIRES; t++) A[i][n] += b->J[t][i] * u[t];
    }
    for (k = 0; k < n; k++) {
        int p = k;
        for (i = k + 1; i < n; i++) if (fabs(A[i][k]) > fabs(A[p][k])) p = i;
        if (p != k)
            for (j = k; j <= n; j++) {
                double tmp = A[k][j];
                A[k][j] = A[p][j];
                A[p][j] = tmp;
            }
        for (i = k + 1; i < n; i++) {
            double f = A[i][k] / A[k][k];
            for (j = k; j <= n; j++) A[i][j] -= f * A[k][j];
        }
    }
    for (i = n - 1; i >= 0; i--) {
        double s = A[i][n];
        for (j = i + 1; j < n; j++) s -= A[i][j] * x[j];
        x[i] = s / A[i][i];
    }
}

/* q'' = M^-1 J^T (F - W) from the forces set last. */
static void accelerations(const double *v, const BodyMatrices *b, double ddq[BODY_COORDINATES]) {
    int t, j;
    for (j = 0; j < BODY_COORDINATES; j++) {
        double s = 0.0;
        for (t = 0; t < BODY_TIRES; t++) s += b->J[t][j] * (v[VR_FORCE_FL + t] - v[VR_LOAD_FL + t]);
        ddq[j] = b->minv[j] * s;
    }
}

void cleatfmu_body_outputs(double *v, double time) {
    BodyMatrices b;
    double ddq[BODY_COORDINATES], seat_z = 0.0, seat_az = 0.0, q0[BODY_COORDINATES], dq0[BODY_COORDINATES];
    const double *q = v + ST_Q, *dq = v + ST_DQP;
    int t, j;
    matrices(v, &b);
    if (v[ST_STARTED] == 0.0) {            /* before the first step: the initial values */
        project(&b, v + VR_INITIAL_HUB_DZ_FL, q0);
        project(&b, v + VR_INITIAL_HUB_VZ_FL, dq0);
        q = q0;
        dq = dq0;
    }
    accelerations(v, &b, ddq);
    for (t = 0; t < BODY_TIRES; t++) {
        double z = v[VR_STATIC_HUB_Z_FL + t], vz = 0.0, az = 0.0;
        for (j = 0; j < BODY_COORDINATES; j++) {
            z += b.J[t][j] * q[j];
            vz += b.J[t][j] * dq[j];
            az += b.J[t][j] * ddq[j];
        }
        v[VR_HUB_Z_FL + t] = z;
        v[VR_HUB_VZ_FL + t] = vz;
        v[VR_HUB_AZ_FL + t] = az;
        v[VR_HUB_X_FL + t] = v[VR_START_X] + v[VR_SPEED] * time - (t < 2 ? 0.0 : v[VR_WHEELBASE]);
    }
    for (j = 0; j < BODY_COORDINATES; j++) {
        seat_z += b.seat[j] * q[j];
        seat_az += b.seat[j] * ddq[j];
    }
    v[VR_HUB_VX] = v[VR_SPEED];
    v[VR_SEAT_Z] = seat_z;
    v[VR_SEAT_AZ] = seat_az;
}

void cleatfmu_body_step(double *v, double h) {
    BodyMatrices b;
    double ddq1[BODY_COORDINATES], hh2 = 0.5 * h * h;
    double *q = v + ST_Q, *dqp = v + ST_DQP, *dq = v + ST_DQ, *ddq = v + ST_DDQ;
    int j;
    matrices(v, &b);
    accelerations(v, &b, ddq1);
    if (v[ST_STARTED] == 0.0) {            /* the first step starts from the initial values */
        project(&b, v + VR_INITIAL_HUB_DZ_FL, q);
        project(&b, v + VR_INITIAL_HUB_VZ_FL, dq);
        for (j = 0; j < BODY_COORDINATES; j++) ddq[j] = ddq1[j];
        v[ST_STARTED] = 1.0;
    } else {                               /* complete the last step with the forces at its end */
        double last = 0.5 * v[ST_LAST_STEP];
        for (j = 0; j < BODY_COORDINATES; j++) {
            dq[j] = dq[j] + last * (ddq[j] + ddq1[j]);
            ddq[j] = ddq1[j];
        }
    }
    for (j = 0; j < BODY_COORDINATES; j++) {
        q[j] = q[j] + h * dq[j] + hh2 * ddq[j];
        dqp[j] = dq[j] + h * ddq[j];
    }
    v[ST_LAST_STEP] = h;
}

#endif
