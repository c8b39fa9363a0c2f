/* cli.h — sub-commands of the irrcache command; each returns the process exit status. */
#ifndef IC_CLI_H
#define IC_CLI_H

/* irrcache render SCENE -o OUT [options] */
int ic_cli_render(int argc, char **argv);
/* irrcache diff A B [--json] [--heatmap FILE.png] */
int ic_cli_diff(int argc, char **argv);
/* irrcache points SCENE --points FILE|- [-o FILE] [--format text|csv|json] */
int ic_cli_points(int argc, char **argv);

#endif
