"""Master algorithm coupling the gear-shaft and bearing slaves; CLI."""
