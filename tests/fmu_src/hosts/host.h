/*
 * What the test hosts of tests/fmu_src/hosts share: a logger that writes the FMU's messages to
 * stderr, the callbacks, OPEN_FMU, which opens the FMU's binary from its unzipped folder
 * (declaring binary, resources and lib) or returns 1, and RESOLVE, which takes an FMI function
 * from it or returns 2; the messages name the host (HOST_NAME).
 */
#ifndef GSB_TEST_HOST_H
#define GSB_TEST_HOST_H

#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "fmi/fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "[%s %d %s] ", name ? name : "", (int)status, category ? category : "");
    vfprintf(stderr, message, args);
    fprintf(stderr, "\n");
    va_end(args);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

#define OPEN_FMU(folder, model)                                                        \
    char binary[4096], resources[4096];                                                \
    snprintf(binary, sizeof binary, "%s/binaries/linux64/%s.so", folder, model);       \
    snprintf(resources, sizeof resources, "file://%s/resources", folder);              \
    void* lib = dlopen(binary, RTLD_NOW | RTLD_LOCAL);                                 \
    if (lib == NULL) {                                                                 \
        fprintf(stderr, HOST_NAME ": %s\n", dlerror());                                \
        return 1;                                                                      \
    }

#define RESOLVE(var, type, name)                                                       \
    type* var = (type*)dlsym(lib, name);                                               \
    if (var == NULL) {                                                                 \
        fprintf(stderr, HOST_NAME ": %s lacks %s\n", binary, name);                   \
        return 2;                                                                      \
    }

#endif
