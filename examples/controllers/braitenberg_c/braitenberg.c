/* A Braitenberg wanderer written as embedded C against rilbed's register map: it reads
 * the eight proximity registers and writes the two motor registers, nothing else. The
 * controller itself (braitenberg_init, _step, _cleanup) builds unchanged for a
 * microcontroller whose rilbed_peek and rilbed_poke read the real hardware; the last
 * lines make it a rilbed plug-in library. rilbed's own `c:braitenberg` is this file, built
 * beside rilbed; docs/write-a-controller.md walks through it. */
#include <stddef.h>

#include <rilbed/rilbed_controller.h>

/* Weights from each proximity sensor to each wheel, per 1023 of reading (sensor 0 is on
 * the left): an obstacle on the left speeds the left wheel and slows the right one. */
static const int32_t kLeftWeights[8] = {4, 6, 8, -8, -6, -4, 0, 0};
static const int32_t kRightWeights[8] = {-4, -6, -8, 8, 6, 4, 0, 0};
enum { kCruise = 10, kMaxSpeed = 20, kAvoidThreshold = 200 };

static void braitenberg_init(void) {
  rilbed_poke(RILBED_REG_MOTOR_LEFT, 0);
  rilbed_poke(RILBED_REG_MOTOR_RIGHT, 0);
  rilbed_poke(RILBED_REG_USER_0, 0); /* steps taken, per robot */
}

static int32_t clamp(int32_t v, int32_t lo, int32_t hi) { return v < lo ? lo : (v > hi ? hi : v); }

static void braitenberg_step(void) {
  int32_t left = kCruise * 1023, right = kCruise * 1023, nearest = 0;
  for (uint32_t i = 0; i < 8; ++i) {
    int32_t p = rilbed_peek(RILBED_REG_PROX_0 + i);
    if (p < 0) p = 0;
    if (p > nearest) nearest = p;
    left += kLeftWeights[i] * p;
    right += kRightWeights[i] * p;
  }
  rilbed_poke(RILBED_REG_MOTOR_LEFT, clamp(left / 1023, -kMaxSpeed, kMaxSpeed));
  rilbed_poke(RILBED_REG_MOTOR_RIGHT, clamp(right / 1023, -kMaxSpeed, kMaxSpeed));
  rilbed_poke(RILBED_REG_BEHAVIOUR, nearest > kAvoidThreshold ? 1 : 0);
  rilbed_poke(RILBED_REG_USER_0, rilbed_peek(RILBED_REG_USER_0) + 1);
}

static void braitenberg_cleanup(void) {
  rilbed_poke(RILBED_REG_MOTOR_LEFT, 0);
  rilbed_poke(RILBED_REG_MOTOR_RIGHT, 0);
}

/* The plug-in library: the ABI version and rilbed's peek and poke (once per library), and
 * the list of the controllers it holds, ended by NULL. */
RILBED_DEFINE_PLUGIN();

static const rilbed_c_controller braitenberg = {"braitenberg", braitenberg_init, braitenberg_step, braitenberg_cleanup};

const rilbed_c_controller* const* rilbed_controllers(void) {
  static const rilbed_c_controller* const list[] = {&braitenberg, NULL};
  return list;
}
