# Examples of the eval area.
