/*
 * die.c
 *		How ./tdc fails: one line "tdc: ..." on stderr, then the exit code
 *		(1: the input or the run, 2: the command line).  The temporary files
 *		of a bounded run go with the exit (atexit, bounded_files.c).
 */
#include <stdio.h>
#include <stdlib.h>

#include "cli.h"

void
die(int code, const char *fmt, const char *arg)
{
	fprintf(stderr, "tdc: ");
	fprintf(stderr, fmt, arg);
	fputc('\n', stderr);
	exit(code);
}
