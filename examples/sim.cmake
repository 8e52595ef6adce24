# Examples of the sim area.
