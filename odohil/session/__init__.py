"""Layer 4: trials, journal, measurement sources, live estimates."""
