"""Back ends of the command line: each turns a subcommand's parsed options into calls of the
science modules and the file-format modules, and returns the summary text `pipeline.py` prints."""
