/*
 * A minimal FMI 2.0 co-simulation host without Python that drives the gear-shaft FMU of a
 * train of nb bearings as the package's master does: fmi2SetReal of the 14 nb law inputs,
 * fmi2DoStep, fmi2GetReal of the 4 nb journal outputs, with a saved state restored among the
 * steps. Built by tests/fmu_src/test_structure_host.py:
 *
 *   structure_host <unzipped FMU> <model identifier> <guid> <dt> <steps> <save at> <restore at>
 *                  <nb> <14 nb law value references> <4 nb journal value references>
 *                  <14 nb values of law A> <14 nb values of law B>
 *
 * In initialisation it sets law A and reads the static solution's journals; then step k
 * (from 0) sets law A for odd k, B for even k, steps from k dt and reads the journals. After
 * step <save at> it saves the state (fmi2GetFMUstate); after step <restore at> it restores it
 * and reads the journals, then steps on from the saved time, the same laws again. Each read
 * prints one line: what it followed ("static", "step k", "restored"), the statuses of the
 * calls and the 4 nb journal values as C99 hexadecimal floats (exact), so that the test compares
 * them bit for bit with the in-process structure. The FMU's loader loads libpython; the
 * patched library serves the sets and reads while stepping from the slave's buffer
 * (fmu_src/native/patches/0012-native-structure-io.patch).
 */
#define HOST_NAME "structure_host"
#include "host.h"

static int N_LAWS, N_JOURNALS;

static void print_values(const fmi2Real* v)
{
    for (int i = 0; i < N_JOURNALS; ++i) printf(" %a", v[i]);
    printf("\n");
}

int main(int argc, char** argv)
{
    int nb = argc > 8 ? atoi(argv[8]) : 0;
    N_LAWS = 14 * nb;
    N_JOURNALS = 4 * nb;
    const int fixed = 9 + N_LAWS + N_JOURNALS;
    if (nb < 1 || argc != fixed + 2 * N_LAWS) {
        fprintf(stderr, "usage: structure_host <unzipped FMU> <model identifier> <guid> <dt> "
                        "<steps> <save at> <restore at> <nb> <14 nb law vrs> <4 nb journal vrs> "
                        "<14 nb values of law A> <14 nb values of law B>\n");
        return 64;
    }
    OPEN_FMU(argv[1], argv[2])
    RESOLVE(instantiate, fmi2InstantiateTYPE, "fmi2Instantiate")
    RESOLVE(setup, fmi2SetupExperimentTYPE, "fmi2SetupExperiment")
    RESOLVE(enter, fmi2EnterInitializationModeTYPE, "fmi2EnterInitializationMode")
    RESOLVE(exit_init, fmi2ExitInitializationModeTYPE, "fmi2ExitInitializationMode")
    RESOLVE(set_real, fmi2SetRealTYPE, "fmi2SetReal")
    RESOLVE(get_real, fmi2GetRealTYPE, "fmi2GetReal")
    RESOLVE(do_step, fmi2DoStepTYPE, "fmi2DoStep")
    RESOLVE(get_state, fmi2GetFMUstateTYPE, "fmi2GetFMUstate")
    RESOLVE(set_state, fmi2SetFMUstateTYPE, "fmi2SetFMUstate")
    RESOLVE(free_state, fmi2FreeFMUstateTYPE, "fmi2FreeFMUstate")
    RESOLVE(term, fmi2TerminateTYPE, "fmi2Terminate")
    RESOLVE(free_, fmi2FreeInstanceTYPE, "fmi2FreeInstance")
    double dt = strtod(argv[4], NULL);
    int steps = atoi(argv[5]), save_at = atoi(argv[6]), restore_at = atoi(argv[7]);
    fmi2ValueReference* in = malloc(N_LAWS * sizeof(fmi2ValueReference));
    fmi2ValueReference* out = malloc(N_JOURNALS * sizeof(fmi2ValueReference));
    fmi2Real* laws[2] = {malloc(N_LAWS * sizeof(fmi2Real)), malloc(N_LAWS * sizeof(fmi2Real))};
    fmi2Real* journals = malloc(N_JOURNALS * sizeof(fmi2Real));
    for (int i = 0; i < N_LAWS; ++i) in[i] = (fmi2ValueReference)strtoul(argv[9 + i], NULL, 10);
    for (int i = 0; i < N_JOURNALS; ++i)
        out[i] = (fmi2ValueReference)strtoul(argv[9 + N_LAWS + i], NULL, 10);
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < N_LAWS; ++i) laws[j][i] = strtod(argv[fixed + j * N_LAWS + i], NULL);
    fmi2Component c = instantiate("structure_host", fmi2CoSimulation, argv[3], resources,
                                  &callbacks, fmi2False, fmi2True);
    if (c == NULL) {
        fprintf(stderr, "structure_host: fmi2Instantiate returned NULL\n");
        return 3;
    }
    if (setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK || enter(c) != fmi2OK) {
        fprintf(stderr, "structure_host: initialisation failed\n");
        return 3;
    }
    fmi2Status set = set_real(c, in, N_LAWS, laws[0]);
    fmi2Status got = get_real(c, out, N_JOURNALS, journals);
    printf("static %d %d", (int)set, (int)got);
    print_values(journals);
    if (exit_init(c) != fmi2OK) {
        fprintf(stderr, "structure_host: fmi2ExitInitializationMode failed\n");
        return 3;
    }
    fmi2FMUstate saved = NULL;
    int k = 0, restored = 0;
    while (k < steps) {
        set = set_real(c, in, N_LAWS, laws[k % 2 ? 0 : 1]);
        fmi2Status stepped = do_step(c, k * dt, dt, fmi2True);
        got = get_real(c, out, N_JOURNALS, journals);
        printf("step %d %d %d %d", k, (int)set, (int)stepped, (int)got);
        print_values(journals);
        if (k == save_at && saved == NULL && get_state(c, &saved) != fmi2OK) {
            fprintf(stderr, "structure_host: fmi2GetFMUstate failed\n");
            return 3;
        }
        if (k == restore_at && !restored) {
            restored = 1;
            fmi2Status back = set_state(c, saved);
            got = get_real(c, out, N_JOURNALS, journals);
            printf("restored %d %d", (int)back, (int)got);
            print_values(journals);
            k = save_at + 1;
            continue;
        }
        ++k;
    }
    if (saved != NULL) free_state(c, &saved);
    fflush(stdout);
    printf("terminate %d\n", (int)term(c));
    free_(c);
    return 0;
}
