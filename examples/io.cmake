# Examples of the io area.
