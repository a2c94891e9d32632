/* rilbed's actuator-model API (paper 000 §6.6): how a virtual robot's wheels turn its
 * controller's commands into motion, as a plug-in library (rilbed/plugin.h) that a
 * scenario puts on a robot:
 *
 *   robots:
 *     - ids: 1-5
 *       actuator: {library: build/differential_drive.so, name: differential_drive, parameters: slip.txt}
 *
 * Each step of the world (the physics step), the model gets the wheel commands the
 * controller last wrote (its motor registers) and says how fast each wheel then moves
 * over the ground for that step, and what the wheel counters count; rilbed drives the
 * exact arc those speeds make and resolves collisions. Without a model a robot has the
 * built-in differential drive with slip (a scenario's `noise:`), which
 * examples/actuators/differential_drive rebuilds as a plug-in.
 *
 * One instance per robot: a model may keep the robot's own state (a motor's speed, a
 * battery) in it. Noise comes from rilbed, from the robot's own stream at that step.
 * Real robots move by themselves: a scenario gives actuators to virtual robots only. */
#ifndef RILBED_ACTUATOR_MODEL_H
#define RILBED_ACTUATOR_MODEL_H

#include <stdint.h>

#include "rilbed/plugin.h"
#include "rilbed/sensor_model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A key of an actuator model's parameter file: the same struct, file formats and rules as
 * a sensor model's (rilbed/sensor_model.h). */
typedef rilbed_sensor_param rilbed_actuator_param;

/* What create() gets, for one robot. Pointers valid during the call only. */
typedef struct rilbed_actuator_setup {
  int32_t robot_id;
  uint32_t param_count;       /* the model's parameters, every one, in its declared order */
  const double* param_values; /* with the defaults filled in */
  double wheel_base_m;        /* the robot's distance between its wheels */
  int64_t step_us;            /* the world's physics step: how often drive() is called */
  const rilbed_static_world* world;
  const char* parameter_file; /* where the parameters came from, for messages */
} rilbed_actuator_setup;

/* One step: the commands and the robot as the step begins. */
typedef struct rilbed_drive_call {
  int64_t t_us; /* the step's start, simulated */
  int32_t robot_id;
  double x_m, y_m, heading_rad;    /* its pose, field frame */
  double dt_s;                     /* the step's length */
  int32_t left_units, right_units; /* the motor registers: Khepera units (8 mm/s), +-127 */
  double left_command_mps;         /* the same, in m/s */
  double right_command_mps;
  void* noise;                    /* the robot's noise stream at this step */
  double (*normal)(void* noise);  /* a standard normal draw from it */
  double (*uniform)(void* noise); /* a uniform draw in [0, 1) */
} rilbed_drive_call;

/* What the wheels do over the step. rilbed fills in the commanded speeds before the
 * call: a model changes what it models. */
typedef struct rilbed_drive_output {
  double left_mps, right_mps;                 /* the wheels' speeds over the ground */
  double left_counted_mps, right_counted_mps; /* what the wheel counters count (odometry) */
} rilbed_drive_output;

/* An actuator model: what it is, and its three functions. `error` (of `error_size` bytes)
 * takes a NUL-terminated message when a function fails; rilbed names the library and the
 * robot around it. */
typedef struct rilbed_actuator_model {
  uint32_t abi_version; /* RILBED_ABI_VERSION */
  const char* name;     /* what a scenario names: `actuator: {..., name: <name>}` */
  const char* summary;  /* one line of what it models */
  const rilbed_actuator_param* params;
  uint32_t param_count;
  int32_t concurrent; /* 1: drive() may run for several robots at once (each instance is one robot's) */
  /* One robot's instance; NULL (with `error` set) when it cannot. */
  void* (*create)(const rilbed_actuator_setup* setup, char* error, uint32_t error_size);
  /* One step; 0 on success, anything else (with `error` set) ends the run. */
  int32_t (*drive)(void* model, const rilbed_drive_call* call, rilbed_drive_output* output, char* error,
                   uint32_t error_size);
  void (*destroy)(void* model); /* once, when the robot leaves the world */
} rilbed_actuator_model;

/* The actuator models a library holds: a list ended by NULL, valid while it is loaded. */
RILBED_EXPORT const rilbed_actuator_model* const* rilbed_actuator_models(void);

#ifdef __cplusplus
}
#endif

#endif /* RILBED_ACTUATOR_MODEL_H */
