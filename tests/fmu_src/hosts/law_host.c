/*
 * A minimal FMI 2.0 co-simulation host without Python that drives a bearing FMU as the
 * package's master does in a coupled iteration: fmi2SetReal of the four journal-state inputs,
 * then fmi2GetReal of the ten law outputs. Built by tests/fmu_src/test_law_host.py:
 *
 *   law_host <unzipped FMU> <model identifier> <guid> <4 state value references>
 *            <10 law value references> <states, 4 numbers each ...>
 *
 * For each state it prints one line: the status of the read and the ten values as C99
 * hexadecimal floats (exact), so that the test compares them bit for bit with the model in
 * its own process. The FMU's loader loads libpython; the patched library serves these calls
 * with the compiled law (fmu_src/native/patches/0011-native-bearing-law.patch).
 */
#define HOST_NAME "law_host"
#include "host.h"

int main(int argc, char** argv)
{
    if (argc < 18 || (argc - 18) % 4 != 0) {
        fprintf(stderr, "usage: law_host <unzipped FMU> <model identifier> <guid> "
                        "<4 state vrs> <10 law vrs> <states, 4 numbers each>\n");
        return 64;
    }
    OPEN_FMU(argv[1], argv[2])
    RESOLVE(instantiate, fmi2InstantiateTYPE, "fmi2Instantiate")
    RESOLVE(setup, fmi2SetupExperimentTYPE, "fmi2SetupExperiment")
    RESOLVE(enter, fmi2EnterInitializationModeTYPE, "fmi2EnterInitializationMode")
    RESOLVE(exit_init, fmi2ExitInitializationModeTYPE, "fmi2ExitInitializationMode")
    RESOLVE(set_real, fmi2SetRealTYPE, "fmi2SetReal")
    RESOLVE(get_real, fmi2GetRealTYPE, "fmi2GetReal")
    RESOLVE(term, fmi2TerminateTYPE, "fmi2Terminate")
    RESOLVE(free_, fmi2FreeInstanceTYPE, "fmi2FreeInstance")
    fmi2ValueReference in[4], out[10];
    for (int i = 0; i < 4; ++i) in[i] = (fmi2ValueReference)strtoul(argv[4 + i], NULL, 10);
    for (int i = 0; i < 10; ++i) out[i] = (fmi2ValueReference)strtoul(argv[8 + i], NULL, 10);
    fmi2Component c = instantiate("law_host", fmi2CoSimulation, argv[3], resources, &callbacks,
                                  fmi2False, fmi2True); /* logging on: the failed read's reason */
    if (c == NULL) {
        fprintf(stderr, "law_host: fmi2Instantiate returned NULL\n");
        return 3;
    }
    if (setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK || enter(c) != fmi2OK
        || exit_init(c) != fmi2OK) {
        fprintf(stderr, "law_host: initialisation failed\n");
        return 3;
    }
    for (int k = 18; k < argc; k += 4) {
        fmi2Real state[4], law[10];
        for (int i = 0; i < 4; ++i) state[i] = strtod(argv[k + i], NULL);
        fmi2Status set = set_real(c, in, 4, state);
        fmi2Status got = get_real(c, out, 10, law);
        printf("%d %d", (int)set, (int)got);
        for (int i = 0; i < 10; ++i) printf(" %a", law[i]);
        printf("\n");
    }
    fflush(stdout);
    printf("terminate %d\n", (int)term(c));
    free_(c);
    return 0;
}
