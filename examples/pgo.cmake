# Examples of the pgo area.
