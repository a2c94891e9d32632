/* rilbed's controller API for C (and the C side of rilbed/controller.hpp for C++).
 *
 * A C controller is written in the spirit of SPREAD's memory-mapped I/O (paper 000 §5.2,
 * §6.5): it reads its sensors with rilbed_peek() and drives its motors with rilbed_poke()
 * on a per-robot register map, between an init and a cleanup call. An embedded-style C
 * controller written against these registers compiles unchanged for the simulator:
 * rilbed calls init once, step once per control period, cleanup once at the end, each
 * with the registers of the robot being controlled current.
 *
 * One process runs many robots with the same controller, so C static variables are
 * shared between them: keep per-robot state in the user registers (RILBED_REG_USER_0..),
 * which are the robot's own memory and start at 0. (Such controllers are stepped one at a
 * time even on `--threads N`, for the same reason.)
 *
 * A library of them (a shared object that writes RILBED_DEFINE_PLUGIN() once, see
 * rilbed/plugin.h) exports them with rilbed_controllers(); a scenario names one with
 * `controller: {library: path/to/lib.so, name: NAME}`. A library may instead, or as well,
 * export controller classes (rilbed_controller_class below): controllers with numeric
 * parameters that rilbed checks, per-robot state of their own, and the whole of a
 * control step's input as a struct; rilbed/controller.hpp writes those for C++. */
#ifndef RILBED_CONTROLLER_H
#define RILBED_CONTROLLER_H

#include <stdint.h>

#include "rilbed/plugin.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Register addresses. R: read only, W: written by the controller, RW: both. */
enum rilbed_register {
  RILBED_REG_ID = 0x00,              /* R: the robot's ID */
  RILBED_REG_TIME_MS = 0x01,         /* R: simulated time, milliseconds (wraps at 2^31) */
  RILBED_REG_PERIOD_MS = 0x02,       /* R: control period, milliseconds */
  RILBED_REG_PROX_0 = 0x10,          /* R: proximity sensors 0..7 at 0x10..0x17, 0..1023 (-1: none) */
  RILBED_REG_ODO_LEFT = 0x20,        /* R: left wheel counter, pulses of 0.08 mm (low 32 bits) */
  RILBED_REG_ODO_RIGHT = 0x21,       /* R: right wheel counter */
  RILBED_REG_RANGE_COUNT = 0x28,     /* R: number of range finders (up to 8) */
  RILBED_REG_RANGE_0 = 0x30,         /* R: range finder i at 0x30+i, millimetres; -1: nothing in range */
  RILBED_REG_TRACK_COUNT = 0x38,     /* R: number of track sensors (up to 16) */
  RILBED_REG_TRACK_ON = 0x39,        /* R: 1 when a track sensor reads at least half its Max Value, else 0 */
  RILBED_REG_TRACK_OFFSET_UM = 0x3A, /* R: where the tape lies across the sensors, micrometres left of the
                                        robot's axis (the mean of those that see it); 0 when off */
  RILBED_REG_TRACK_ARMS = 0x3B,      /* R: side arms: bit 0 left, bit 1 right (a sensor farther out than a 20 mm
                                        tape's edge sees tape while one in the middle does: a junction or a corner) */
  RILBED_REG_TRACK_0 = 0x40,         /* R: track sensor i at 0x40+i, 0..its Max Value */
  RILBED_REG_BEACON_COUNT = 0x50,    /* R: number of beacons in view (up to 8) */
  RILBED_REG_BEACON_0 = 0x60,        /* R: beacon i: ID at 0x60+2i, bearing at 0x61+2i in millidegrees CCW from ahead */
  RILBED_REG_POSE_VALID = 0x70,      /* R: 1 if the pose registers hold the robot's pose */
  RILBED_REG_POSE_X_MM = 0x71,       /* R: field x, millimetres */
  RILBED_REG_POSE_Y_MM = 0x72,       /* R: field y, millimetres */
  RILBED_REG_POSE_HEADING_MDEG = 0x73, /* R: heading, millidegrees CCW from +x, [0, 360000) */
  RILBED_REG_MOTOR_LEFT = 0x80,        /* RW: left wheel speed, Khepera units (pulses/10 ms, clamped to +-127) */
  RILBED_REG_MOTOR_RIGHT = 0x81,       /* RW: right wheel speed */
  RILBED_REG_BEHAVIOUR = 0x82,         /* RW: behaviour code shown in the run's records (0 = "c0", ... 7 = "c7") */
  RILBED_REG_USER_0 = 0x100,           /* RW: 256 words of per-robot memory, 0x100..0x1FF */
  RILBED_REG_MODEL_COUNT = 0x200,      /* R: number of sensor-model values at RILBED_REG_MODEL_0.. (up to 256) */
  RILBED_REG_MODEL_0 = 0x210,          /* R: the sensor models' values (rilbed/sensor_model.h), mount after mount,
                                          in thousandths (value x 1000, rounded); track-providing ones are in TRACK */
  RILBED_REG_COUNT = 0x310             /* one past the last address */
};

/* Value at `address` of the current robot's register map; 0 for an address outside it
 * or outside a controller's call. */
RILBED_HIDDEN int32_t rilbed_peek(uint32_t address);

/* Writes `value` at `address`. Writes to read-only or unknown addresses are ignored
 * (and counted, so that rilbed can warn about them). */
RILBED_HIDDEN void rilbed_poke(uint32_t address, int32_t value);

/* A C controller: three functions rilbed calls with the robot's registers current. */
typedef struct rilbed_c_controller {
  const char* name;      /* the name a scenario gives: `controller: {library: ..., name: <name>}` */
  void (*init)(void);    /* once, before the first step (sensor registers already filled); may be NULL */
  void (*step)(void);    /* once per control period */
  void (*cleanup)(void); /* once when the run ends; may be NULL */
} rilbed_c_controller;

/* The C controllers a library holds: a list ended by NULL, valid while the library is
 * loaded. Defined by the library (optional if it exports rilbed_controller_classes()). */
RILBED_EXPORT const rilbed_c_controller* const* rilbed_controllers(void);

/* ------------------------------------------------------------------ controller classes */

/* One number a controller class takes from a robot's `params` in a scenario. rilbed
 * checks every value against it before the controller is made, and prints it in
 * `rilbed controllers` and the web editor's forms. */
typedef struct rilbed_param {
  const char* name;     /* the key in `params`, with its unit in it: "speed_mps", "gain" */
  const char* unit;     /* "m/s", "m", "deg", ...; "" for a count, an ID or a level */
  const char* summary;  /* one line of what it means */
  double default_value; /* used when the scenario leaves it out, if has_default */
  int32_t has_default;  /* 0: the controller decides (say how in summary), or it is required */
  int32_t required;     /* 1: the scenario must give it (then has_default must be 0) */
  int32_t integer;      /* 1: whole numbers only */
  double min;           /* smallest allowed value, inclusive; -HUGE_VAL for none */
  double max;           /* largest allowed value, inclusive; HUGE_VAL for none */
} rilbed_param;

/* What a class's create() gets for one robot. Pointers valid during the call only. */
typedef struct rilbed_controller_args {
  int32_t robot_id;     /* the robot it will control */
  uint32_t param_count; /* the class's parameters that have a value, given or default */
  const char* const* param_names;
  const double* param_values;
  const int32_t* param_given; /* 1 where the scenario gave the value, 0 for a default */
} rilbed_controller_args;

/* One ultrasonic range finder's reading. */
typedef struct rilbed_range {
  int32_t hit;       /* 0: nothing within range */
  double distance_m; /* to the nearest object; the range when !hit */
} rilbed_range;

/* An IR beacon in view of the direction finder. */
typedef struct rilbed_beacon {
  int32_t id;
  double bearing_rad; /* counter-clockwise from the robot's forward direction, [-pi, pi) */
} rilbed_beacon;

/* One member of the team broadcast. */
typedef struct rilbed_team_member {
  int32_t id;
  double x_m, y_m, heading_rad; /* field frame: metres, radians counter-clockwise from +x */
  const char* behaviour;        /* its active behaviour ("follow", ...) */
  int64_t t_us;                 /* when the pose was true */
} rilbed_team_member;

/* The readings of one sensor model the robot carries (rilbed/sensor_model.h), by the
 * name its scenario mounts it under. */
typedef struct rilbed_model_reading {
  const char* model;
  const double* values;
  uint32_t count;
} rilbed_model_reading;

/* Everything a controller gets at one control step. Arrays hold `*_count` elements;
 * every pointer is valid during the step call only. */
typedef struct rilbed_control_input {
  int64_t t_us;     /* simulated time of this step, microseconds */
  int32_t robot_id; /* the robot being controlled */
  int32_t has_pose; /* 1: x_m, y_m, heading_rad hold its pose from localisation (world or camera) */
  double x_m, y_m, heading_rad;
  int32_t has_proximity; /* 1: proximity[] holds the eight IR sensors, 0..1023, left to right then back */
  int32_t proximity[8];
  int32_t has_odometry; /* 1: the wheel counters, pulses of 0.08 mm */
  int64_t odometry_left_pulses, odometry_right_pulses;
  const rilbed_range* ranges; /* the range finders, in configured order */
  uint32_t range_count;
  const int32_t* track; /* the track sensors, 0..their max value, in configured order */
  uint32_t track_count;
  const rilbed_beacon* beacons; /* beacons in view */
  uint32_t beacon_count;
  const rilbed_team_member* team; /* the latest team broadcast; empty unless the class wants_team */
  uint32_t team_count;
  const rilbed_model_reading* models; /* the sensor models' readings */
  uint32_t model_count;
} rilbed_control_input;

/* What a controller decides at one step. */
typedef struct rilbed_control_output {
  int32_t left, right;   /* wheel speeds, Khepera units (pulses per 10 ms, 8 mm/s each); clamped to +-127 */
  const char* behaviour; /* the active behaviour, shown in the run's records; NULL: "idle". rilbed copies it */
} rilbed_control_output;

/* A controller class: what it is, for the registry, and how to make, step and destroy
 * one controller per robot. `error` (of `error_size` bytes) takes a NUL-terminated
 * message when a function fails; rilbed names the library and the robot around it. */
typedef struct rilbed_controller_class {
  uint32_t abi_version; /* RILBED_ABI_VERSION */
  const char* name;     /* the name a scenario gives */
  const char* summary;  /* one line of what it does */
  const rilbed_param* params;
  uint32_t param_count;
  const char* const* sensors;          /* what it reads, NULL-terminated: "proximity", "range_finders",
                                          "beacon_finder", "track", "odometer", "pose"; may be NULL */
  const char* const* required_sensors; /* of those, what a robot must carry; NULL-terminated, may be NULL */
  int32_t wants_team;                  /* 1: it reads the team broadcast (a copy of every member per step) */
  int32_t concurrent;  /* 1: its robots' steps may run at once on `--threads N` (no shared mutable state) */
  const void* context; /* passed back to create() */
  /* Makes one robot's controller; NULL (with `error` set) when it cannot. */
  void* (*create)(const void* context, const rilbed_controller_args* args, char* error, uint32_t error_size);
  /* One control step; 0 on success, anything else (with `error` set) ends the run. */
  int32_t (*step)(void* controller, const rilbed_control_input* input, rilbed_control_output* output, char* error,
                  uint32_t error_size);
  void (*finish)(void* controller);        /* once after the last step; may be NULL */
  int32_t (*done)(const void* controller); /* 1 once it reached its goal; may be NULL */
  void (*destroy)(void* controller);       /* frees it */
} rilbed_controller_class;

/* The controller classes a library holds: a list ended by NULL, valid while the library
 * is loaded; NULL if the library could not make it. Defined by the library (optional if
 * it exports rilbed_controllers()). */
RILBED_EXPORT const rilbed_controller_class* const* rilbed_controller_classes(void);

#ifdef __cplusplus
}
#endif

#endif /* RILBED_CONTROLLER_H */
