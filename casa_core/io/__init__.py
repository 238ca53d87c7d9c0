"""Files: the trial-log contract, its reader and writer, validation, and atomic output."""
