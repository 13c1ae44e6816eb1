/*
 * gear-shaft-bearing addition (not part of pythonfmu): the FMU's binary as a C/C++ host loads
 * it, a loader in front of the pythonfmu library (linux64 only).
 *
 * pythonfmu's library uses the Python C API without linking libpython: it loads only into a
 * process where Python's symbols are already global (a Python host such as fmpy). In a C/C++
 * host (ecos, OMSimulator, FMUSim ...) dlopen fails or the first Python call crashes. This
 * loader has no Python dependency. At the first fmi2Instantiate it
 *
 *   1. leaves everything as it is when Python is already in the process (Py_IsInitialized
 *      found among the global symbols);
 *   2. otherwise loads libpython with RTLD_GLOBAL (so that numpy's and scipy's extension
 *      modules find its symbols too) and sets the interpreter's program name to a Python
 *      executable, so that the embedded interpreter sees that executable's environment (a
 *      virtual environment's site-packages included). Both paths come from the environment
 *      variables GSB_LIBPYTHON and GSB_PYTHON, else from resources/gsb_python.txt, written
 *      when the FMU was built (the build's Python);
 *   3. loads the pythonfmu library (libpythonfmu-export.so beside this file) and forwards
 *      every FMI call to it.
 *
 * A failure is reported through the host's logger callback and fmi2Instantiate returns NULL.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <wchar.h>

#include "fmi/fmi2Functions.h"

#define IMPL_NAME "libpythonfmu-export.so"
#define CONFIG_NAME "gsb_python.txt"

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static void* impl = NULL;
static char message[4096];

#define FMI_FUNCTIONS(X) \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetDebugLogging) X(fmi2SetupExperiment) \
    X(fmi2EnterInitializationMode) X(fmi2ExitInitializationMode) X(fmi2Terminate) \
    X(fmi2Reset) X(fmi2GetReal) X(fmi2GetInteger) X(fmi2GetBoolean) X(fmi2GetString) \
    X(fmi2SetReal) X(fmi2SetInteger) X(fmi2SetBoolean) X(fmi2SetString) \
    X(fmi2GetFMUstate) X(fmi2SetFMUstate) X(fmi2FreeFMUstate) \
    X(fmi2SerializedFMUstateSize) X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate) \
    X(fmi2GetDirectionalDerivative) X(fmi2SetRealInputDerivatives) \
    X(fmi2GetRealOutputDerivatives) X(fmi2DoStep) X(fmi2CancelStep) X(fmi2GetStatus) \
    X(fmi2GetRealStatus) X(fmi2GetIntegerStatus) X(fmi2GetBooleanStatus) \
    X(fmi2GetStringStatus)

#define DECLARE(name) static name##TYPE* p_##name = NULL;
FMI_FUNCTIONS(DECLARE)

/* the folder of this library, with a trailing slash */
static int own_folder(char* out, size_t size)
{
    Dl_info info;
    if (!dladdr((void*)&own_folder, &info) || info.dli_fname == NULL) return 0;
    const char* slash = strrchr(info.dli_fname, '/');
    size_t n = slash ? (size_t)(slash - info.dli_fname + 1) : 0;
    if (n + 1 > size) return 0;
    memcpy(out, info.dli_fname, n);
    out[n] = '\0';
    return 1;
}

/* "file:///a%20b/" -> "/a b/" */
static void uri_to_path(const char* uri, char* out, size_t size)
{
    if (strncmp(uri, "file://", 7) == 0) uri += 7;
    else if (strncmp(uri, "file:", 5) == 0) uri += 5;
    size_t n = 0;
    for (; *uri && n + 1 < size; ++uri) {
        if (uri[0] == '%' && uri[1] && uri[2]) {
            char hex[3] = {uri[1], uri[2], 0};
            out[n++] = (char)strtol(hex, NULL, 16);
            uri += 2;
        } else {
            out[n++] = *uri;
        }
    }
    out[n] = '\0';
}

/* value of "key=" in resources/gsb_python.txt (empty if absent) */
static void config_value(const char* resources, const char* key, char* out, size_t size)
{
    char path[4096];
    out[0] = '\0';
    snprintf(path, sizeof path, "%s%s%s", resources,
             resources[0] && resources[strlen(resources) - 1] == '/' ? "" : "/", CONFIG_NAME);
    FILE* f = fopen(path, "r");
    if (!f) return;
    char line[4096];
    size_t klen = strlen(key);
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, key, klen) == 0 && line[klen] == '=') {
            char* value = line + klen + 1;
            value[strcspn(value, "\r\n")] = '\0';
            snprintf(out, size, "%s", value);
            break;
        }
    }
    fclose(f);
}

static int python_in_process(void)
{
    return dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL;
}

/* load libpython globally and name the interpreter's executable (C/C++ hosts) */
static int load_python(const char* resources)
{
    char libpython[4096], executable[4096];
    const char* env = getenv("GSB_LIBPYTHON");
    if (env && *env) snprintf(libpython, sizeof libpython, "%s", env);
    else config_value(resources, "libpython", libpython, sizeof libpython);
    env = getenv("GSB_PYTHON");
    if (env && *env) snprintf(executable, sizeof executable, "%s", env);
    else config_value(resources, "executable", executable, sizeof executable);
    if (!libpython[0]) {
        snprintf(message, sizeof message, "no libpython to load: set GSB_LIBPYTHON to the "
                 "shared Python library (e.g. libpython3.11.so.1.0) of a Python with numpy, "
                 "scipy and numba");
        return 0;
    }
    if (!dlopen(libpython, RTLD_NOW | RTLD_GLOBAL)) {
        snprintf(message, sizeof message, "cannot load libpython %s (GSB_LIBPYTHON or "
                 "resources/" CONFIG_NAME "): %s", libpython, dlerror());
        return 0;
    }
    int (*is_initialized)(void) = (int (*)(void))dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    if (is_initialized && !is_initialized() && executable[0]) {
        typedef wchar_t* decode_t(const char*, size_t*);
        typedef void set_name_t(const wchar_t*);
        decode_t* decode = (decode_t*)dlsym(RTLD_DEFAULT, "Py_DecodeLocale");
        set_name_t* set_name = (set_name_t*)dlsym(RTLD_DEFAULT, "Py_SetProgramName");
        if (decode && set_name) {
            wchar_t* name = decode(executable, NULL); /* kept: Python holds on to it */
            if (name) set_name(name);
        }
    }
    return 1;
}

static int load(const char* resource_uri)
{
    if (impl) return 1;
    char folder[4096], path[4096], resources[4096];
    uri_to_path(resource_uri ? resource_uri : "", resources, sizeof resources);
    if (!python_in_process() && !load_python(resources)) return 0;
    if (!own_folder(folder, sizeof folder)) {
        snprintf(message, sizeof message, "cannot locate the FMU's binary folder");
        return 0;
    }
    snprintf(path, sizeof path, "%s%s", folder, IMPL_NAME);
    void* handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        snprintf(message, sizeof message, "cannot load %s: %s", path, dlerror());
        return 0;
    }
#define RESOLVE(name) \
    p_##name = (name##TYPE*)dlsym(handle, #name); \
    if (!p_##name) { \
        snprintf(message, sizeof message, "%s lacks %s", path, #name); \
        return 0; \
    }
    FMI_FUNCTIONS(RESOLVE)
    impl = handle;
    return 1;
}

const char* fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char* fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions* functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    pthread_mutex_lock(&lock);
    int ok = load(fmuResourceLocation);
    pthread_mutex_unlock(&lock);
    if (!ok) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Fatal,
                              "logError", "%s", message);
        else
            fprintf(stderr, "%s: %s\n", instanceName ? instanceName : "FMU", message);
        return NULL;
    }
    return p_fmi2Instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation, functions,
                             visible, loggingOn);
}

void fmi2FreeInstance(fmi2Component c) { if (p_fmi2FreeInstance) p_fmi2FreeInstance(c); }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                               const fmi2String categories[])
{ return p_fmi2SetDebugLogging(c, on, n, categories); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{ return p_fmi2SetupExperiment(c, toleranceDefined, tolerance, startTime, stopTimeDefined,
                               stopTime); }

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{ return p_fmi2EnterInitializationMode(c); }

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{ return p_fmi2ExitInitializationMode(c); }

fmi2Status fmi2Terminate(fmi2Component c) { return p_fmi2Terminate(c); }

fmi2Status fmi2Reset(fmi2Component c) { return p_fmi2Reset(c); }

#define GETSET(type) \
    fmi2Status fmi2Get##type(fmi2Component c, const fmi2ValueReference vr[], size_t n, \
                             fmi2##type value[]) \
    { return p_fmi2Get##type(c, vr, n, value); } \
    fmi2Status fmi2Set##type(fmi2Component c, const fmi2ValueReference vr[], size_t n, \
                             const fmi2##type value[]) \
    { return p_fmi2Set##type(c, vr, n, value); }
GETSET(Real)
GETSET(Integer)
GETSET(Boolean)
GETSET(String)

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{ return p_fmi2GetFMUstate(c, state); }

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{ return p_fmi2SetFMUstate(c, state); }

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{ return p_fmi2FreeFMUstate(c, state); }

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size)
{ return p_fmi2SerializedFMUstateSize(c, state, size); }

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size)
{ return p_fmi2SerializeFMUstate(c, state, bytes, size); }

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate* state)
{ return p_fmi2DeSerializeFMUstate(c, bytes, size, state); }

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknown[],
                                        size_t n_unknown, const fmi2ValueReference known[],
                                        size_t n_known, const fmi2Real dv_known[],
                                        fmi2Real dv_unknown[])
{ return p_fmi2GetDirectionalDerivative(c, unknown, n_unknown, known, n_known, dv_known,
                                        dv_unknown); }

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[])
{ return p_fmi2SetRealInputDerivatives(c, vr, n, order, value); }

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real value[])
{ return p_fmi2GetRealOutputDerivatives(c, vr, n, order, value); }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior)
{ return p_fmi2DoStep(c, t, h, no_prior); }

fmi2Status fmi2CancelStep(fmi2Component c) { return p_fmi2CancelStep(c); }

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value)
{ return p_fmi2GetStatus(c, s, value); }

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value)
{ return p_fmi2GetRealStatus(c, s, value); }

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value)
{ return p_fmi2GetIntegerStatus(c, s, value); }

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value)
{ return p_fmi2GetBooleanStatus(c, s, value); }

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value)
{ return p_fmi2GetStringStatus(c, s, value); }
