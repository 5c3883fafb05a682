/* A model-exchange host without Python for valgrind: instantiates a native FMU for model exchange,
 * takes its directional derivatives in initialisation and continuous-time mode (all derivatives and
 * outputs with respect to all states and inputs, and none) and checks that the calls the standard
 * leaves to the FMU to refuse are refused (a parameter as a known, a state as an unknown, an undeclared
 * value reference, NULL arrays, a non-finite seed). Used by tests/fmu/test_native_fmu.py.
 *
 * native_me_host DIR MODEL_ID GUID N_IN N_OUT FIRST_STATE N_STATES PARAMETER_VR
 *   states' value references FIRST_STATE .. FIRST_STATE + N_STATES - 1, their derivatives' the next
 *   N_STATES; inputs 0 .. N_IN - 1, outputs N_IN .. N_IN + N_OUT - 1.
 * Prints "unexpected statuses <n>"; exit status 1 if the FMU cannot be loaded or instantiated.
 */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "silent_fmi2_host.h"

int main(int argc, char **argv) {
    char path[4096], uri[4096];
    void *lib;
    fmi2Component c;
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2EventInfo info;
    size_t i, n_in, n_out, first, nx;
    fmi2ValueReference parameter;
    double *x, *dx, *seed, *out;
    fmi2ValueReference *known, *unknown;
    int unexpected = 0;
    if (argc != 9) return 2;
    n_in = strtoul(argv[4], NULL, 10);
    n_out = strtoul(argv[5], NULL, 10);
    first = strtoul(argv[6], NULL, 10);
    nx = strtoul(argv[7], NULL, 10);
    parameter = (fmi2ValueReference)strtoul(argv[8], NULL, 10);
    snprintf(path, sizeof(path), "%s/binaries/linux64/%s.so", argv[1], argv[2]);
    snprintf(uri, sizeof(uri), "file://%s/resources", argv[1]);
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) return 1;
    {
        LOAD(fmi2Instantiate) LOAD(fmi2FreeInstance) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationMode) LOAD(fmi2NewDiscreteStates) LOAD(fmi2EnterContinuousTimeMode)
        LOAD(fmi2SetContinuousStates) LOAD(fmi2GetDerivatives) LOAD(fmi2GetDirectionalDerivative) LOAD(fmi2Terminate)
        c = fmi2Instantiate("me", fmi2ModelExchange, argv[3], uri, &callbacks, fmi2False, fmi2False);
        if (!c) return 1;
        x = (double *)calloc(nx, sizeof(double));
        dx = (double *)calloc(nx, sizeof(double));
        seed = (double *)calloc(nx + n_in, sizeof(double));
        out = (double *)calloc(nx + n_out, sizeof(double));
        known = (fmi2ValueReference *)calloc(nx + n_in, sizeof(fmi2ValueReference));
        unknown = (fmi2ValueReference *)calloc(nx + n_out, sizeof(fmi2ValueReference));
        fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
        fmi2EnterInitializationMode(c);
        for (i = 0; i < n_in; i++) {
            known[i] = (fmi2ValueReference)i;
            seed[i] = 1.0 + (double)i;
        }
        for (i = 0; i < n_out; i++) unknown[i] = (fmi2ValueReference)(n_in + i);
        unexpected += fmi2GetDirectionalDerivative(c, unknown, n_out, known, n_in, seed, out) != fmi2OK;
        fmi2ExitInitializationMode(c);
        fmi2NewDiscreteStates(c, &info);
        fmi2EnterContinuousTimeMode(c);
        for (i = 0; i < nx; i++) x[i] = 1e-3 * (double)(i % 7);
        unexpected += fmi2SetContinuousStates(c, x, nx) != fmi2OK;
        unexpected += fmi2GetDerivatives(c, dx, nx) != fmi2OK;
        for (i = 0; i < nx; i++) {
            known[i] = (fmi2ValueReference)(first + i);
            seed[i] = 0.5;
            unknown[i] = (fmi2ValueReference)(first + nx + i);
        }
        for (i = 0; i < n_in; i++) {
            known[nx + i] = (fmi2ValueReference)i;
            seed[nx + i] = 1.0;
        }
        for (i = 0; i < n_out; i++) unknown[nx + i] = (fmi2ValueReference)(n_in + i);
        unexpected += fmi2GetDirectionalDerivative(c, unknown, nx + n_out, known, nx + n_in, seed, out) != fmi2OK;
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 0, known, 0, seed, out) != fmi2OK;
        /* refused */
        known[0] = parameter;
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 1, known, 1, seed, out) != fmi2Error;
        known[0] = (fmi2ValueReference)first;
        unknown[0] = (fmi2ValueReference)first;
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 1, known, 1, seed, out) != fmi2Error;
        unknown[0] = (fmi2ValueReference)(first + 2 * nx + 1000);
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 1, known, 1, seed, out) != fmi2Error;
        unknown[0] = (fmi2ValueReference)(first + nx);
        unexpected += fmi2GetDirectionalDerivative(c, NULL, 1, known, 1, seed, out) != fmi2Error;
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 1, known, 1, seed, NULL) != fmi2Error;
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 1, known, 1, NULL, out) != fmi2Error;
        seed[0] = NAN;
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 1, known, 1, seed, out) != fmi2Error;
        fmi2Terminate(c);
        unexpected += fmi2GetDirectionalDerivative(c, unknown, 1, known + 1, 1, seed + 1, out) != fmi2OK;
        fmi2FreeInstance(c);
        free(x);
        free(dx);
        free(seed);
        free(out);
        free(known);
        free(unknown);
    }
    dlclose(lib);
    printf("unexpected statuses %d\n", unexpected);
    return 0;
}
