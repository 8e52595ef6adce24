# Examples of the register area.
