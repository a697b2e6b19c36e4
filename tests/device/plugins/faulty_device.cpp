// A device plug-in that misbehaves on request, for the loader's tests. It holds still at the
// origin with button 1 pressed from the start and, from time `after` (s) on, does one of:
//   fault=nan    returns a NaN position        fault=quat  returns a quaternion of norm 2
//   fault=block  sleeps `block_ms` in read()   fault=fail  returns -1 from read()
//   fault=segv   dies of SIGSEGV in read()     fault=none  (default) behaves
//   fault=abort  calls abort() in its `reads`-th read() (counted from 1), whatever the time
// With log=PATH every wrench written is appended to PATH, one "fx fy fz tx ty tz" line each;
// with open_block_ms=N its open() sleeps N ms first (a device that does not answer).
// Built a second time with FAULTY_ABI_VERSION=99 to claim an ABI this Torsion does not speak.

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "torsion/device/plugin_abi.h"

#ifndef FAULTY_ABI_VERSION
#define FAULTY_ABI_VERSION TORSION_DEVICE_ABI_VERSION
#endif

namespace {

struct Faulty {
  std::string fault = "none";
  double after = 0;
  double block_ms = 50;
  long abort_at = 0;
  long reads = 0;
  long writes = 0;
  std::FILE* log = nullptr;
};

void* openDevice(const char* config, char* error, size_t error_size) {
  Faulty* d = new Faulty;
  std::string text = config ? config : "";
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find(',', start);
    if (end == std::string::npos) end = text.size();
    const std::string item = text.substr(start, end - start);
    const size_t eq = item.find('=');
    const std::string key = item.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : item.substr(eq + 1);
    if (key == "fault")
      d->fault = value;
    else if (key == "after")
      d->after = std::atof(value.c_str());
    else if (key == "block_ms")
      d->block_ms = std::atof(value.c_str());
    else if (key == "reads")
      d->abort_at = std::atol(value.c_str());
    else if (key == "log")
      d->log = std::fopen(value.c_str(), "a");
    else if (key == "open_block_ms")
      std::this_thread::sleep_for(
          std::chrono::duration<double, std::milli>(std::atof(value.c_str())));
    else {
      std::snprintf(error, error_size, "faulty device: unknown key '%s'", key.c_str());
      delete d;
      return nullptr;
    }
    start = end + 1;
  }
  return d;
}

int info(void*, torsion_device_info* out) {
  out->max_force = 20;
  out->max_torque = 2;
  out->rate_hz = 1000;
  std::snprintf(out->name, sizeof out->name, "faulty");
  return 0;
}

int read(void* handle, double time, torsion_device_state* out) {
  Faulty& d = *static_cast<Faulty*>(handle);
  if (d.fault == "abort" && ++d.reads >= d.abort_at) std::abort();
  std::memset(out, 0, sizeof *out);
  out->orientation[0] = 1;
  out->buttons = 1;
  out->alive = 1;
  if (time < d.after || d.fault == "none") return 0;
  if (d.fault == "nan") out->position[0] = std::nan("");
  if (d.fault == "quat") out->orientation[0] = 2;
  if (d.fault == "fail") return -1;
  if (d.fault == "segv") std::raise(SIGSEGV);  // as a stray pointer would, but on cue
  if (d.fault == "block")
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(d.block_ms));
  return 0;
}

int write(void* handle, const double* wrench) {
  Faulty& d = *static_cast<Faulty*>(handle);
  ++d.writes;
  if (d.log) {
    std::fprintf(d.log, "%.17g %.17g %.17g %.17g %.17g %.17g\n", wrench[0], wrench[1], wrench[2],
                 wrench[3], wrench[4], wrench[5]);
    std::fflush(d.log);
  }
  return 0;
}

void closeDevice(void* handle) {
  Faulty* d = static_cast<Faulty*>(handle);
  if (d->log) std::fclose(d->log);
  delete d;
}

const torsion_device_v1 kTable = {FAULTY_ABI_VERSION, 0, openDevice, info, read, write,
                                  closeDevice};

}  // namespace

extern "C" __attribute__((visibility("default"))) const torsion_device_v1* torsion_device_plugin(
    void) {
  return &kTable;
}
