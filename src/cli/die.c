/*
 * die.c
 *		How ./tdc fails: one line "tdc: ..." on stderr, then the exit code
 *		(1: the input or the run, 2: the command line).  The temporary files
 *		of a bounded run go with the exit (atexit, bounded_files.c).
 */
#include <pthread.h>
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

/*
 * A callback's failure, msg, kept in first (firstlen bytes) unless one is
 * there already: the emits of both tile workers may fail at once
 * (emit_concurrent), and the run reports the first.
 */
void
keep_first_error(pthread_mutex_t *mu, char *first, size_t firstlen, const char *msg)
{
	pthread_mutex_lock(mu);
	if (first[0] == '\0')
		snprintf(first, firstlen, "%s", msg);
	pthread_mutex_unlock(mu);
}
