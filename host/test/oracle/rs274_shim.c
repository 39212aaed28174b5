/* LD_PRELOAD helper for LinuxCNC's standalone interpreter `rs274` (package linuxcnc-uspace), used
 * only by the oracle test (docs/oracle.md). rs274 prints every canonical machine command with
 * "%.4f"; this library widens those numbers to "%.17g" (every double exact) and, after the
 * output-line counter that starts each printed command, inserts "L<line> " with the interpreter's
 * current source line (Interp::sequence_number() of the global `pinterp` that rs274 exports).
 * Nothing else changes: the interpreter, its inputs and its errors are LinuxCNC's own. */
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

int __fprintf_chk(FILE* stream, int flag, const char* fmt, ...) {
  char buf[1024];
  va_list ap;
  int r;
  (void)flag;
  va_start(ap, fmt);
  r = vfprintf(stream, stream == stdout ? widen(fmt, buf, sizeof buf) : fmt, ap);
  va_end(ap);
  if (stream == stdout && strcmp(fmt, "%5d ") == 0) {
    char line[32];
    snprintf(line, sizeof line, "L%d ", source_line());
    fputs(line, stream); /* not fprintf: that may be this very function under _FORTIFY_SOURCE */
  }
  return r;
}
