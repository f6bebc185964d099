"""The registered env presets spelt out for reading, as package data (``EnvConfig.from_yaml``)."""
