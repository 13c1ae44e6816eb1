"""pythonfmu slave classes exposing the physics as FMI 2.0 co-simulation FMUs."""
