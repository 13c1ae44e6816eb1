/*
 * A minimal FMI 2.0 co-simulation host that leaves fmi2Terminate and fmi2FreeInstance to the
 * process's exit, as OMSimulator's Python API does when a script ends without terminate() /
 * delete() (its C++ static destructors make the calls). Built by
 * tests/fmu_src/test_exit_hosts.py, two ways:
 *
 *   - with -DEXIT_HOST_MAIN, a program without Python:
 *       exit_host <unzipped FMU> <model identifier> <guid> <steps>
 *     (the FMU's loader loads libpython);
 *   - as a shared library that a Python process loads with ctypes and calls
 *       exit_host_start(<unzipped FMU>, <model identifier>, <guid>, <steps>, <how>)
 *     then ends: Python finalises its interpreter, and only then do C's exit handlers run.
 *
 * exit_host_start instantiates the FMU, initialises it, takes <steps> steps and registers the
 * calls to come at exit: an atexit() handler (how 0) or this library's destructor (how 1,
 * shared library only). At exit they print "exit: fmi2Terminate <status>" and
 * "exit: fmi2FreeInstance done" on stdout, so that the test knows they ran.
 */
#define HOST_NAME "exit_host"
#include "host.h"

#include <string.h>

static fmi2Component instance = NULL;
static fmi2TerminateTYPE* terminate_ = NULL;
static fmi2FreeInstanceTYPE* free_instance = NULL;
static int at_destructor = 0;

static void end_instance(void)
{
    if (instance == NULL) return;
    fmi2Status status = terminate_(instance);
    printf("exit: fmi2Terminate %d\n", (int)status);
    fflush(stdout);
    free_instance(instance);
    instance = NULL;
    printf("exit: fmi2FreeInstance done\n");
    fflush(stdout);
}

__attribute__((destructor)) static void at_unload(void)
{
    if (at_destructor) end_instance();
}

#define CHECK(call)                                                                    \
    if ((call) != fmi2OK) {                                                            \
        fprintf(stderr, "exit_host: %s failed\n", #call);                             \
        return 3;                                                                      \
    }

/* 0 when the instance is running and its end registered; else what failed (stderr says) */
int exit_host_start(const char* folder, const char* model, const char* guid, int steps,
                    int how)
{
    OPEN_FMU(folder, model)
    RESOLVE(instantiate, fmi2InstantiateTYPE, "fmi2Instantiate")
    RESOLVE(setup, fmi2SetupExperimentTYPE, "fmi2SetupExperiment")
    RESOLVE(enter, fmi2EnterInitializationModeTYPE, "fmi2EnterInitializationMode")
    RESOLVE(exit_init, fmi2ExitInitializationModeTYPE, "fmi2ExitInitializationMode")
    RESOLVE(do_step, fmi2DoStepTYPE, "fmi2DoStep")
    RESOLVE(term, fmi2TerminateTYPE, "fmi2Terminate")
    RESOLVE(free_, fmi2FreeInstanceTYPE, "fmi2FreeInstance")
    terminate_ = term;
    free_instance = free_;
    instance = instantiate("exit_host", fmi2CoSimulation, guid, resources, &callbacks,
                           fmi2False, fmi2False);
    if (instance == NULL) {
        fprintf(stderr, "exit_host: fmi2Instantiate returned NULL\n");
        return 3;
    }
    CHECK(setup(instance, fmi2False, 0.0, 0.0, fmi2False, 0.0))
    CHECK(enter(instance))
    CHECK(exit_init(instance))
    for (int k = 0; k < steps; ++k) {
        CHECK(do_step(instance, k * 1e-4, 1e-4, fmi2True))
    }
    if (how == 1) {
        at_destructor = 1;
    } else if (atexit(end_instance) != 0) {
        fprintf(stderr, "exit_host: atexit failed\n");
        return 4;
    }
    return 0;
}

#ifdef EXIT_HOST_MAIN
int main(int argc, char** argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: exit_host <unzipped FMU> <model identifier> <guid> <steps>\n");
        return 64;
    }
    int status = exit_host_start(argv[1], argv[2], argv[3], atoi(argv[4]), 0);
    printf("main: returns %d\n", status);
    fflush(stdout);
    return status;
}
#endif
