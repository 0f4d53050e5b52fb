#include "cli/cli.h"
#include "common.h"
int mx_check_main(int argc, char **argv) { (void)argc; (void)argv; mx_error(NULL, 0, "check: not implemented yet"); return MX_EINPUT; }
