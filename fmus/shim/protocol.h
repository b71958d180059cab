/* Generated from fmus/protocol.py by `agilesat generate`: do not edit. */
#ifndef AGILESAT_PROTOCOL_H
#define AGILESAT_PROTOCOL_H

/* derivative calls */
#define DERIVATIVE_BASE 1073741824
#define ORDER_SHIFT 24
#define MAX_ORDER 63

/* the handshake */
#define FAST_PATH_VR 4294967295u
#define FAST_PATH_N 6
#define FAST_PATH_VERSION 8.0

/* kind[]: per scalar */
#define KIND_OTHER 0
#define KIND_PARAMETER 1
#define KIND_OUTPUT 2
#define KIND_INPUT 3
#define KIND_FEEDTHROUGH 4
#define KIND_INTEGER 5
#define KIND_BOOLEAN 6
#define KIND_INTEGER_INPUT 7
#define KIND_INTEGER_FEEDTHROUGH 8
#define KIND_BOOLEAN_INPUT 9
#define KIND_BOOLEAN_FEEDTHROUGH 10

/* control[] (int32) */
#define STEP_MODE 0
#define OUTPUTS_VALID 1
#define C_STEP 2
#define C_OUTPUT 3
#define C_DIRTY 4
#define N_CONTROL 5

/* control[C_STEP] */
#define C_STEP_PYTHON 0
#define C_STEP_ENTRY 1
#define C_STEP_TIME 2

/* block[] (float64) */
#define B_TIME 0
#define B_STEP 1
#define B_OUTPUT 2
#define B_STATE 3
#define B_N_STATE 4
#define B_SAVED 5
#define B_N_SAVED 6
#define B_OUTPUTS_START 7
#define B_OUTPUTS_STOP 8
#define B_STEP_END 9
#define B_N_STEP_END 10
#define B_STOP 11
#define B_N_KEPT 12
#define N_BLOCK 13

/* time continuity (math.isclose) */
#define TIME_REL_TOL 1e-09
#define TIME_ABS_TOL 1e-12

#endif
