"""evpose's browser-based viewer (viser): browse, step and tune the EV-Pose tracker, live.

Start it with ``evpose app``; build it programmatically with
``app.server.ViewerApp(app.server.AppConfig(...))``. ``evpose/`` never imports
this package.
"""
