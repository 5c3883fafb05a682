/* A minimal FMI 2.0 co-simulation host without Python: loads a native FMU's binary (dlopen, or
 * LoadLibrary when built for Windows, where the tests run it under wine),
 * instantiates it, sets parameters, steps it with inputs read from a file and writes the
 * outputs to a file. Used by tests/fmu/test_native_fmu.py (results, valgrind) and
 * benchmarks/bench_fmu.py (the time per step).
 *
 * native_host DIR MODEL_ID GUID STEP N_STEPS INPUTS.bin OUTPUTS.bin IN_VRS OUT_VRS [CYCLES [vr=value ...]]
 *   DIR        the extracted FMU; the binary is DIR/binaries/linux64/MODEL_ID.so (win64/MODEL_ID.dll)
 *   INPUTS.bin N_STEPS x n_in doubles (row k: the inputs held over step k)
 *   OUTPUTS.bin gets (N_STEPS + 1) x n_out doubles: the outputs at t = 0, STEP, ..., N_STEPS STEP
 *   IN_VRS, OUT_VRS comma-separated value references; CYCLES instantiate/run/free cycles (default 1)
 *   vr=value   parameters set in initialization mode
 * Prints "seconds_per_step <s>" (the step loop of the last cycle) on stdout; exit status 1 on any
 * FMI error (its message is printed by the logger on stderr).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

#ifdef _WIN32
#include <windows.h>
#define BINARY "binaries/win64/%s.dll"
#define URI "file:///%s/resources"
static void *open_library(const char *path) { return (void *)LoadLibraryA(path); }
static void *symbol(void *lib, const char *name) { return (void *)GetProcAddress((HMODULE)lib, name); }
static void close_library(void *lib) { FreeLibrary((HMODULE)lib); }
static const char *library_error(void) { return "LoadLibrary failed"; }
static double now(void) {
    LARGE_INTEGER count, frequency;
    QueryPerformanceCounter(&count);
    QueryPerformanceFrequency(&frequency);
    return (double)count.QuadPart / (double)frequency.QuadPart;
}
#else
#include <dlfcn.h>
#define BINARY "binaries/linux64/%s.so"
#define URI "file://%s/resources"
static void *open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(void *lib, const char *name) { return dlsym(lib, name); }
static void close_library(void *lib) { dlclose(lib); }
static const char *library_error(void) { return dlerror(); }
static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
#endif

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    va_list args;
    (void)env;
    fprintf(stderr, "[%s] status %d, %s: ", name, (int)status, category);
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

static size_t parse_list(const char *text, fmi2ValueReference **out) {
    size_t n = 1, k = 0;
    const char *p;
    for (p = text; *p; p++) n += (*p == ',');
    *out = (fmi2ValueReference *)calloc(n, sizeof(fmi2ValueReference));
    for (p = text; *p;) {
        (*out)[k++] = (fmi2ValueReference)strtoul(p, (char **)&p, 10);
        if (*p == ',') p++;
    }
    return k;
}

#define LOAD(name)                                                  \
    name##TYPE *name = (name##TYPE *)symbol(lib, #name);             \
    if (!name) {                                                    \
        fprintf(stderr, "missing symbol %s\n", #name);              \
        return 1;                                                   \
    }

#define CHECK(call)                                                 \
    if ((call) != fmi2OK) {                                         \
        fprintf(stderr, "%s failed\n", #call);                      \
        return 1;                                                   \
    }

int main(int argc, char **argv) {
    const char *dir, *id, *guid;
    double h, *u, *y, elapsed = 0.0;
    long n_steps, k, cycles = 1, cycle;
    size_t n_in, n_out, i;
    fmi2ValueReference *in_vr, *out_vr;
    char path[4096], uri[4200];
    void *lib;
    FILE *f;
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    if (argc < 10) {
        fprintf(stderr, "usage: %s DIR MODEL_ID GUID STEP N_STEPS INPUTS OUTPUTS IN_VRS OUT_VRS [CYCLES [vr=value ...]]\n",
                argv[0]);
        return 2;
    }
    dir = argv[1];
    id = argv[2];
    guid = argv[3];
    h = atof(argv[4]);
    n_steps = atol(argv[5]);
    n_in = parse_list(argv[8], &in_vr);
    n_out = parse_list(argv[9], &out_vr);
    if (argc > 10) cycles = atol(argv[10]);
    u = (double *)calloc((size_t)n_steps * n_in + 1, sizeof(double));
    y = (double *)calloc(((size_t)n_steps + 1) * n_out, sizeof(double));
    f = fopen(argv[6], "rb");
    if (!f || fread(u, sizeof(double), (size_t)n_steps * n_in, f) != (size_t)n_steps * n_in) {
        fprintf(stderr, "cannot read %s\n", argv[6]);
        return 2;
    }
    fclose(f);
    snprintf(path, sizeof(path), "%s/" BINARY, dir, id);
    snprintf(uri, sizeof(uri), URI, dir);
    lib = open_library(path);
    if (!lib) {
        fprintf(stderr, "loading %s: %s\n", path, library_error());
        return 1;
    }
    {
        LOAD(fmi2Instantiate)
        LOAD(fmi2SetupExperiment)
        LOAD(fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationMode)
        LOAD(fmi2SetReal)
        LOAD(fmi2GetReal)
        LOAD(fmi2DoStep)
        LOAD(fmi2Terminate)
        LOAD(fmi2FreeInstance)
        for (cycle = 0; cycle < cycles; cycle++) {
            double t0;
            fmi2Component c = fmi2Instantiate("host", fmi2CoSimulation, guid, uri, &callbacks, fmi2False, fmi2False);
            if (!c) return 1;
            CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0))
            CHECK(fmi2EnterInitializationMode(c))
            for (i = 11; i < (size_t)argc; i++) {
                fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[i], NULL, 10);
                const char *eq = strchr(argv[i], '=');
                fmi2Real value;
                if (!eq) return 2;
                value = atof(eq + 1);
                CHECK(fmi2SetReal(c, &vr, 1, &value))
            }
            CHECK(fmi2ExitInitializationMode(c))
            CHECK(fmi2GetReal(c, out_vr, n_out, y))
            t0 = now();
            for (k = 0; k < n_steps; k++) {
                CHECK(fmi2SetReal(c, in_vr, n_in, u + (size_t)k * n_in))
                CHECK(fmi2DoStep(c, (double)k * h, h, fmi2True))
                CHECK(fmi2GetReal(c, out_vr, n_out, y + ((size_t)k + 1) * n_out))
            }
            elapsed = now() - t0;
            CHECK(fmi2Terminate(c))
            fmi2FreeInstance(c);
        }
    }
    f = fopen(argv[7], "wb");
    if (!f || fwrite(y, sizeof(double), ((size_t)n_steps + 1) * n_out, f) != ((size_t)n_steps + 1) * n_out) {
        fprintf(stderr, "cannot write %s\n", argv[7]);
        return 2;
    }
    fclose(f);
    printf("seconds_per_step %.6g\n", n_steps ? elapsed / (double)n_steps : 0.0);
    close_library(lib);
    free(u);
    free(y);
    free(in_vr);
    free(out_vr);
    return 0;
}
