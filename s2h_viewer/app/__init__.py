"""The desktop application: main window, actions, background work, settings (`s2h view`)."""
