"""Ground apps (central agent), hosted on the same executive model as the flight software."""
