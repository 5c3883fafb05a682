/* What the POSIX test hosts that drive the native runtime through its error paths share: a logger
 * that discards the FMU's messages (the statuses are what they check) and a macro that looks an FMI 2
 * function up in the loaded library (dlsym), leaving main with status 1 when it is missing. */
#ifndef SILENT_FMI2_HOST_H
#define SILENT_FMI2_HOST_H

#include <dlfcn.h>
#include <stdio.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    (void)name;
    (void)status;
    (void)category;
    (void)message;
}

#define LOAD(name)                                              \
    name##TYPE *name = (name##TYPE *)dlsym(lib, #name);         \
    if (!name) {                                                \
        fprintf(stderr, "missing symbol %s\n", #name);          \
        return 1;                                               \
    }

#endif
