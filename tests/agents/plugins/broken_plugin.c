/* Plug-in libraries that are wrong in one way each, for the loader's errors
 * (test_library_controllers.cpp); BROKEN says which, one library per value. */
#include <stddef.h>

#include <rilbed/rilbed_controller.h>

#if BROKEN == 1 /* built against another ABI version */
RILBED_EXPORT uint32_t rilbed_abi_version(void) { return 999u; }
RILBED_EXPORT void rilbed_plugin_bind(const rilbed_host* host) { (void)host; }
#elif BROKEN == 3 /* not a rilbed plug-in at all: no rilbed_abi_version() */
RILBED_EXPORT int something_else(void) { return 1; }
#else
RILBED_DEFINE_PLUGIN();
#endif

#if BROKEN == 2 /* a symbol that no library loaded defines */
extern int32_t lab_helper_from_elsewhere(void);
static void step(void) { rilbed_poke(RILBED_REG_MOTOR_LEFT, lab_helper_from_elsewhere()); }
#elif BROKEN == 1 || BROKEN == 3 /* no RILBED_DEFINE_PLUGIN(): no rilbed_poke to call */
static void step(void) {}
#else
static void step(void) { rilbed_poke(RILBED_REG_MOTOR_LEFT, 1); }
#endif

#if BROKEN == 3 || BROKEN == 4 /* 4: a plug-in that holds no list */
RILBED_EXPORT int32_t call_step(void) {
  step();
  return 0;
}
#elif BROKEN == 5 /* a list that is NULL */
static const rilbed_c_controller unlisted = {"unlisted", NULL, step, NULL};
const rilbed_c_controller* const* rilbed_controllers(void) { return unlisted.step ? NULL : NULL; }
#elif BROKEN == 6 /* two controllers of one name */
static const rilbed_c_controller twin = {"twin", NULL, step, NULL};
const rilbed_c_controller* const* rilbed_controllers(void) {
  static const rilbed_c_controller* const list[] = {&twin, &twin, NULL};
  return list;
}
#elif BROKEN == 7 /* a class whose parameter contradicts itself (min above max), reading an unknown sensor */
static const rilbed_param params[] = {{"gain", "", "a gain", 0.5, 1, 0, 0, 1.0, 0.0}};
static void* create(const void* context, const rilbed_controller_args* args, char* error, uint32_t size) {
  (void)context, (void)args, (void)error, (void)size;
  step();
  return NULL;
}
static int32_t class_step(void* c, const rilbed_control_input* in, rilbed_control_output* out, char* e, uint32_t n) {
  (void)c, (void)in, (void)out, (void)e, (void)n;
  return 0;
}
static void destroy(void* c) { (void)c; }
static const char* const sensors[] = {"lidar", NULL};
static const rilbed_controller_class bad = {RILBED_ABI_VERSION,
                                            "bad",
                                            "a class that contradicts itself",
                                            params,
                                            1,
                                            sensors,
                                            NULL,
                                            0,
                                            1,
                                            NULL,
                                            create,
                                            class_step,
                                            NULL,
                                            NULL,
                                            destroy};
const rilbed_controller_class* const* rilbed_controller_classes(void) {
  static const rilbed_controller_class* const list[] = {&bad, NULL};
  return list;
}
#elif BROKEN == 8 /* a C controller without a step function */
static const rilbed_c_controller lame = {"lame", step, NULL, NULL};
const rilbed_c_controller* const* rilbed_controllers(void) {
  static const rilbed_c_controller* const list[] = {&lame, NULL};
  return list;
}
#else             /* BROKEN 1 and 2: something to list, had it loaded */
static const rilbed_c_controller fine = {"fine", NULL, step, NULL};
const rilbed_c_controller* const* rilbed_controllers(void) {
  static const rilbed_c_controller* const list[] = {&fine, NULL};
  return list;
}
#endif
