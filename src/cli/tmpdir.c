/*
 * tmpdir.c
 *		The temporary directory of ./tdc --max-memory: made under --tmpdir
 *		(or $TMPDIR, or /tmp) before the input is staged, removed with
 *		whatever is in it at exit, also when ./tdc dies.
 *
 * ./tdc keeps its staged text input there (input.xy, input.z, input.c);
 * the core's bounded run creates and removes its own files in it
 * (tdc_bounded_run in tdc.h).  The directory is the process's, hence its
 * one global.
 */
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"

char		tmp_dir[4096];

/*
 * SIGINT, SIGTERM or SIGHUP while the directory exists: the first sets
 * cli_cancel, which the run in tiles polls (tdc_bounded_params.cancel)
 * and ends with "canceled", so that the exit removes the directory and
 * what is in it (a handler cannot: readdir is not async-signal-safe); a
 * second one ends the process at once.
 */
volatile int cli_cancel;
static const int tmp_sigs[] = {SIGINT, SIGTERM, SIGHUP};

static void
on_signal(int sig)
{
	if (cli_cancel)
	{
		signal(sig, SIG_DFL);
		raise(sig);
		return;
	}
	cli_cancel = sig;
}

/* tmp_dir := a new directory under base; removed at exit, and after a signal */
void
tmp_create(const char *base)
{
	struct sigaction sa,
				old;

	snprintf(tmp_dir, sizeof(tmp_dir), "%s/tdc.XXXXXX", base);
	if (mkdtemp(tmp_dir) == NULL)
	{
		tmp_dir[0] = '\0';
		die(1, "cannot create a temporary directory in %s", base);
	}
	atexit(tmp_cleanup);
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_signal;
	sigemptyset(&sa.sa_mask);
	for (int i = 0; i < 3; i++)
		if (sigaction(tmp_sigs[i], NULL, &old) == 0 && old.sa_handler == SIG_DFL)
			sigaction(tmp_sigs[i], &sa, NULL);
}

void
tmp_cleanup(void)
{
	DIR		   *d;
	struct dirent *e;

	if (tmp_dir[0] == '\0')
		return;
	if ((d = opendir(tmp_dir)) != NULL)
	{
		while ((e = readdir(d)) != NULL)
		{
			char		p[4400];

			if (e->d_name[0] == '.')
				continue;
			snprintf(p, sizeof(p), "%s/%s", tmp_dir, e->d_name);
			unlink(p);
		}
		closedir(d);
	}
	rmdir(tmp_dir);
	tmp_dir[0] = '\0';
	/* no directory, no handler: a signal ends the process again (the caller raises one that came) */
	for (int i = 0; i < 3; i++)
	{
		struct sigaction old;

		if (sigaction(tmp_sigs[i], NULL, &old) == 0 && old.sa_handler == on_signal)
			signal(tmp_sigs[i], SIG_DFL);
	}
}

/* Is path one of the temporary directory's files (a staged input the run may drop)? */
bool
tmp_owns(const char *path)
{
	size_t		k = strlen(tmp_dir);

	return k > 0 && strncmp(path, tmp_dir, k) == 0 && path[k] == '/';
}

FILE *
tmp_open(const char *name, const char *mode)
{
	char		p[4400];
	FILE	   *f;

	snprintf(p, sizeof(p), "%s/%s", tmp_dir, name);
	f = fopen(p, mode);
	if (f == NULL)
		die(1, "cannot open temporary file %s", p);
	return f;
}
