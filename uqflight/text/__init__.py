"""Text in and out: what the command line prints (`console`), how figures name outputs and parameters
(`labels`), strict JSON laid out for reading (`json_text`), and text files read within a bound
(`bounded`)."""
