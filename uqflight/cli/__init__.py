"""The `uqflight` command line (`commands`), its checks of file arguments (`arguments`) and its way of ending
the process once a command is done (`fast_exit`)."""
