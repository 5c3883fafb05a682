/* Random FMI 2 call sequences (co-simulation and model exchange) from C, for memory checkers: the
 * statuses are not judged here (tests/fmi_fuzz.py does that against the standard's state tables);
 * this host only drives the native runtime through its error paths (calls out of order, invalid
 * arguments, FMU states of the other interface, edited, truncated and garbage serialised states)
 * so that valgrind can see every allocation freed and no invalid access. POSIX only.
 *
 * native_fuzz_host DIR MODEL_ID GUID N_STATES MAX_VR SEQUENCES LENGTH SEED
 * Prints "sequences S calls C ok K" on stdout; exit status 0 unless the FMU could not be loaded.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "silent_fmi2_host.h"

static unsigned long long rng_state;
static unsigned rnd(unsigned n) { /* n > 0 */
    rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (unsigned)((rng_state >> 33) % n);
}
static double pick(const double *values, unsigned n) { return values[rnd(n)]; }

int main(int argc, char **argv) {
    char path[4096], uri[4096];
    void *lib;
    size_t nx, max_vr, sequences, length, s, k, calls = 0, ok = 0;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    if (argc != 9) {
        fprintf(stderr, "usage: native_fuzz_host DIR MODEL_ID GUID N_STATES MAX_VR SEQUENCES LENGTH SEED\n");
        return 1;
    }
    nx = (size_t)strtoul(argv[4], NULL, 10);
    max_vr = (size_t)strtoul(argv[5], NULL, 10);
    sequences = (size_t)strtoul(argv[6], NULL, 10);
    length = (size_t)strtoul(argv[7], NULL, 10);
    rng_state = strtoull(argv[8], NULL, 10);
    snprintf(path, sizeof(path), "%s/binaries/linux64/%s.so", argv[1], argv[2]);
    snprintf(uri, sizeof(uri), "file://%s/resources", argv[1]);
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 1;
    }
    {
        LOAD(fmi2Instantiate) LOAD(fmi2FreeInstance) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationMode) LOAD(fmi2Terminate) LOAD(fmi2Reset) LOAD(fmi2GetReal) LOAD(fmi2SetReal)
        LOAD(fmi2DoStep) LOAD(fmi2GetFMUstate) LOAD(fmi2SetFMUstate) LOAD(fmi2FreeFMUstate)
        LOAD(fmi2SerializedFMUstateSize) LOAD(fmi2SerializeFMUstate) LOAD(fmi2DeSerializeFMUstate)
        LOAD(fmi2SetTime) LOAD(fmi2SetContinuousStates) LOAD(fmi2GetContinuousStates) LOAD(fmi2GetDerivatives)
        LOAD(fmi2GetNominalsOfContinuousStates) LOAD(fmi2EnterEventMode) LOAD(fmi2NewDiscreteStates)
        LOAD(fmi2EnterContinuousTimeMode) LOAD(fmi2CompletedIntegratorStep) LOAD(fmi2GetRealStatus)
        LOAD(fmi2GetBooleanStatus) LOAD(fmi2GetStatus) LOAD(fmi2SetInteger) LOAD(fmi2GetRealOutputDerivatives)
        const double values[] = {0.0, 0.0, 0.5, -1.0, 1e9, NAN, INFINITY};
        const double steps[] = {1e-3, 2e-3, 1e-2, 0.0, -1e-3, NAN};
        double *x = (double *)calloc(nx + 2, sizeof(double));
        /* the other interface's instance and a state of it: set into this one, it must be refused */
        fmi2Component peer[2];
        fmi2FMUstate peer_state[2] = {NULL, NULL};
        int kind;
        for (kind = 0; kind < 2; kind++) {
            peer[kind] = fmi2Instantiate("peer", (fmi2Type)kind, argv[3], uri, &cb, fmi2False, fmi2False);
            if (!peer[kind]) return 1;
            fmi2SetupExperiment(peer[kind], fmi2False, 0.0, 0.0, fmi2False, 0.0);
            fmi2EnterInitializationMode(peer[kind]);
            fmi2ExitInitializationMode(peer[kind]);
            fmi2GetFMUstate(peer[kind], &peer_state[kind]);
        }
        for (s = 0; s < sequences; s++) {
            const fmi2Type type = (fmi2Type)rnd(2);
            fmi2Component c = fmi2Instantiate("fuzz", type, argv[3], uri, &cb, fmi2False, (fmi2Boolean)rnd(2));
            fmi2FMUstate states[4] = {NULL, NULL, NULL, NULL};
            double t = 0.0;
            if (!c) return 1;
            for (k = 0; k < length; k++) {
                fmi2Status st = fmi2OK;
                fmi2ValueReference vr[4];
                double v[4];
                fmi2Real r;
                fmi2Boolean b1, b2;
                fmi2EventInfo info;
                size_t i, n = 1 + rnd(4), size = 0;
                for (i = 0; i < n; i++) {
                    vr[i] = rnd(8) == 0 ? (fmi2ValueReference)(max_vr + 1 + rnd(3)) : (fmi2ValueReference)rnd((unsigned)max_vr + 1);
                    v[i] = pick(values, 7);
                }
                switch (rnd(24)) {
                    case 0: st = fmi2SetupExperiment(c, (fmi2Boolean)rnd(2), pick(values, 7), t = pick(values, 4),
                                                     (fmi2Boolean)rnd(2), pick(values, 7)); break;
                    case 1: st = fmi2EnterInitializationMode(c); break;
                    case 2: case 3: st = fmi2ExitInitializationMode(c); break;
                    case 4: st = fmi2Terminate(c); break;
                    case 5: st = fmi2Reset(c); t = 0.0; break;
                    case 6: case 7: st = fmi2GetReal(c, vr, n, v); break;
                    case 8: st = fmi2SetReal(c, vr, n, v); break;
                    case 9: case 10: {
                        const double h = pick(steps, 6);
                        st = fmi2DoStep(c, rnd(6) ? t : t - 1e-3, h, fmi2True);
                        if (st == fmi2OK) t += h;
                        break;
                    }
                    case 11: { fmi2FMUstate *slot = &states[rnd(4)]; st = fmi2GetFMUstate(c, slot); break; }
                    case 12: {
                        fmi2FMUstate state = rnd(4) == 0 ? peer_state[rnd(2)] : states[rnd(4)];
                        if (state) st = fmi2SetFMUstate(c, state);
                        break;
                    }
                    case 13: {
                        fmi2FMUstate state = states[rnd(4)], copy = NULL;
                        char *bytes;
                        if (!state || fmi2SerializedFMUstateSize(c, state, &size) != fmi2OK) break;
                        bytes = (char *)malloc(size + 1);
                        fmi2SerializeFMUstate(c, state, bytes, size);
                        switch (rnd(4)) {
                            case 0: bytes[rnd((unsigned)size)] ^= (char)(1u << rnd(8)); break;
                            case 1: for (i = 0; i < size; i++) bytes[i] = (char)rnd(256); break;
                            case 2: size = rnd((unsigned)size); break;
                            default: break;
                        }
                        st = fmi2DeSerializeFMUstate(c, bytes, size, &copy);
                        if (copy) fmi2FreeFMUstate(c, &copy);
                        free(bytes);
                        break;
                    }
                    case 14: { fmi2FMUstate *slot = &states[rnd(4)]; if (*slot) st = fmi2FreeFMUstate(c, slot); break; }
                    case 15: st = fmi2SetTime(c, pick(values, 7)); break;
                    case 16: {
                        const size_t m = nx + rnd(3) - 1;
                        for (i = 0; i < nx + 2; i++) x[i] = rnd(10) ? 1e-6 * (double)rnd(100) : NAN;
                        st = fmi2SetContinuousStates(c, x, m);
                        break;
                    }
                    case 17: st = fmi2GetDerivatives(c, x, nx + rnd(3) - 1); break;
                    case 18: st = fmi2GetContinuousStates(c, x, nx); break;
                    case 19: st = fmi2GetNominalsOfContinuousStates(c, x, nx); break;
                    case 20:
                        switch (rnd(4)) {
                            case 0: st = fmi2EnterEventMode(c); break;
                            case 1: st = fmi2NewDiscreteStates(c, &info); break;
                            case 2: st = fmi2EnterContinuousTimeMode(c); break;
                            default: st = fmi2CompletedIntegratorStep(c, fmi2True, &b1, &b2); break;
                        }
                        break;
                    case 21: st = rnd(2) ? fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &r)
                                         : fmi2GetBooleanStatus(c, fmi2Terminated, &b1); break;
                    case 22: { fmi2Status pending; st = fmi2GetStatus(c, fmi2DoStepStatus, &pending); break; }
                    default: {
                        fmi2Integer iv = 1, order = 1;
                        st = rnd(2) ? fmi2SetInteger(c, vr, rnd(2), &iv)
                                    : fmi2GetRealOutputDerivatives(c, vr, rnd(2), &order, v);
                    }
                }
                calls++;
                ok += st == fmi2OK;
            }
            for (k = 0; k < 4; k++)
                if (states[k]) fmi2FreeFMUstate(c, &states[k]);
            fmi2FreeInstance(c);
        }
        for (kind = 0; kind < 2; kind++) {
            fmi2FreeFMUstate(peer[kind], &peer_state[kind]);
            fmi2FreeInstance(peer[kind]);
        }
        free(x);
    }
    dlclose(lib);
    printf("sequences %lu calls %lu ok %lu\n", (unsigned long)sequences, (unsigned long)calls, (unsigned long)ok);
    return 0;
}
