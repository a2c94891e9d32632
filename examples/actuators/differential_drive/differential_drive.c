/* A Khepera's differential drive with wheel slip (paper 000 §6.6: "a forward kinematic
 * model of the combined effect of the ... wheels and motors ... may include noise effects
 * such as wheel slippage"), written as a rilbed actuator-model plug-in against
 * rilbed/actuator_model.h alone. It is rilbed's own built-in drive (a scenario's
 * `noise: {slip_sd, left_bias, right_bias, odometer_counts_slip}`) rebuilt outside rilbed:
 * the same gains and the same noise draws, so a run with it gives the built-in's
 * trajectories byte for byte. docs/write-a-sensor-model.md ("Actuator models") walks
 * through it.
 *
 * Each step, each wheel turns at its command times a gain of 1 + its bias, plus, with
 * Slip above 0, a normal draw times Slip (left first, then right); the wheel counters
 * count that (Counts Slip = 1) or the command (0). */
#include <stdlib.h>

#include <rilbed/actuator_model.h>

enum { kSlip, kLeftBias, kRightBias, kCountsSlip, kParamCount };

static const rilbed_actuator_param kParams[kParamCount] = {
    {"Slip", "", "standard deviation of each wheel's relative speed error, per step", 0.0, 1, 0, 0.0, 1.0},
    {"Left Bias", "", "the left wheel's systematic relative speed error", 0.0, 1, 0, -0.99, 1.0},
    {"Right Bias", "", "the right wheel's systematic relative speed error", 0.0, 1, 0, -0.99, 1.0},
    {"Counts Slip", "", "1: the wheel counters count the slip; 0: they count the command (odometry drifts)", 1.0, 1, 1,
     0.0, 1.0},
};

typedef struct drive {
  double slip, left_bias, right_bias;
  int counts_slip;
} drive;

static void* drive_create(const rilbed_actuator_setup* setup, char* error, uint32_t error_size) {
  (void)error, (void)error_size;
  drive* d = malloc(sizeof(drive));
  d->slip = setup->param_values[kSlip];
  d->left_bias = setup->param_values[kLeftBias];
  d->right_bias = setup->param_values[kRightBias];
  d->counts_slip = setup->param_values[kCountsSlip] != 0.0;
  return d;
}

static int32_t drive_step(void* model, const rilbed_drive_call* call, rilbed_drive_output* out, char* error,
                          uint32_t error_size) {
  (void)error, (void)error_size;
  const drive* d = model;
  double left_gain = 1.0 + d->left_bias, right_gain = 1.0 + d->right_bias;
  if (d->slip > 0.0) {
    left_gain += d->slip * call->normal(call->noise);
    right_gain += d->slip * call->normal(call->noise);
  }
  out->left_mps = call->left_command_mps * left_gain;
  out->right_mps = call->right_command_mps * right_gain;
  out->left_counted_mps = d->counts_slip ? out->left_mps : call->left_command_mps;
  out->right_counted_mps = d->counts_slip ? out->right_mps : call->right_command_mps;
  return 0;
}

static void drive_destroy(void* model) { free(model); }

RILBED_DEFINE_PLUGIN();

static const rilbed_actuator_model differential_drive = {
    RILBED_ABI_VERSION,
    "differential_drive",
    "two wheels on a common axle, each at its command times 1 + its bias + slip noise",
    kParams,
    kParamCount,
    1, /* each robot's instance is its own */
    drive_create,
    drive_step,
    drive_destroy};

const rilbed_actuator_model* const* rilbed_actuator_models(void) {
  static const rilbed_actuator_model* const list[] = {&differential_drive, NULL};
  return list;
}
