/* LD_PRELOAD helper for LinuxCNC's standalone interpreter `rs274` (package linuxcnc-uspace), used
 * only by the oracle test (docs/oracle.md). rs274 prints every canonical machine command with
 * "%.4f"; this library widens those numbers to "%.17g" (every double exact) and, after the
 * output-line counter that starts each printed command, inserts "L<line> " with the interpreter's
 * current source line (Interp::sequence_number() of the global `pinterp` that rs274 exports).
 * Splines (G5, G5.1, G5.2) reach rs274's NURBS_FEED, which prints only the number of control
 * points: on x86-64 this library also prints the points, "NURBS_FEED(n, x0, y0, w0, x1, ...)",
 * read from the std::vector NURBS_FEED holds in %rbx while it prints (this rs274 build; the
 * vector's element count must match the printed count, else the line is printed as rs274 wrote
 * it and the test fails on it). Nothing else changes: the interpreter, its inputs and its errors
 * are LinuxCNC's own. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static const char* widen(const char* fmt, char* buf, size_t size) {
  size_t o = 0;
  for (const char* p = fmt; *p != '\0'; ++p) {
    if (o + 8 >= size) return fmt; /* too long to rewrite: print as rs274 wrote it */
    if (strncmp(p, "%.4f", 4) == 0) {
      memcpy(buf + o, "%.17g", 5);
      o += 5;
      p += 3;
    } else {
      buf[o++] = *p;
    }
  }
  buf[o] = '\0';
  return buf;
}

static int source_line(void) {
  void** interp = (void**)dlsym(RTLD_DEFAULT, "pinterp");
  int (*sequence_number)(void*) =
      (int (*)(void*))dlsym(RTLD_DEFAULT, "_ZN6Interp15sequence_numberEv");
  if (interp == NULL || *interp == NULL || sequence_number == NULL) return -1;
  return sequence_number(*interp);
}

#if defined(__x86_64__)
/* __fprintf_chk's entry keeps the caller's %rbx (callee-saved: NURBS_FEED's vector pointer) for
 * the C body below. */
__attribute__((visibility("hidden"))) void* shim_caller_rbx;
__attribute__((visibility("hidden"))) int shim_fprintf_chk(FILE* stream, int flag, const char* fmt,
                                                           ...);
__asm__(
    ".globl __fprintf_chk\n"
    ".type __fprintf_chk,@function\n"
    "__fprintf_chk:\n"
    "  movq %rbx, shim_caller_rbx(%rip)\n"
    "  jmp shim_fprintf_chk\n"
    ".size __fprintf_chk, .-__fprintf_chk\n");
#define SHIM_FPRINTF_CHK shim_fprintf_chk
#else
#define SHIM_FPRINTF_CHK __fprintf_chk
#endif

/* rs274's NURBS_FEED(std::vector<CONTROL_POINT>, ...): CONTROL_POINT is {X, Y, W} (24 bytes). */
static int print_nurbs(FILE* stream, const char* name, unsigned long count) {
#if defined(__x86_64__)
  const double* const* vec = (const double* const*)shim_caller_rbx;
  if (vec != NULL && vec[0] != NULL && (unsigned long)(vec[1] - vec[0]) == 3 * count) {
    int r = fprintf(stream, "%s(%lu", name, count);
    for (unsigned long i = 0; i < 3 * count; ++i) fprintf(stream, ", %.17g", vec[0][i]);
    fputs(")\n", stream);
    return r;
  }
#endif
  return fprintf(stream, "%s(%lu, ...)\n", name, count);
}

int SHIM_FPRINTF_CHK(FILE* stream, int flag, const char* fmt, ...) {
  char buf[1024];
  va_list ap;
  int r;
  (void)flag;
  va_start(ap, fmt);
  if (stream == stdout && strcmp(fmt, "%s(%lu, ...)\n") == 0) {
    const char* name = va_arg(ap, const char*);
    const unsigned long count = va_arg(ap, unsigned long);
    va_end(ap);
    if (strcmp(name, "NURBS_FEED") == 0) return print_nurbs(stream, name, count);
    return fprintf(stream, fmt, name, count);
  }
  r = vfprintf(stream, stream == stdout ? widen(fmt, buf, sizeof buf) : fmt, ap);
  va_end(ap);
  if (stream == stdout && strcmp(fmt, "%5d ") == 0) {
    char line[32];
    snprintf(line, sizeof line, "L%d ", source_line());
    fputs(line, stream); /* not fprintf: that may be this very function under _FORTIFY_SOURCE */
  }
  return r;
}
