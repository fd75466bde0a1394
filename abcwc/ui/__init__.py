"""Notebook panels (ipywidgets): the rider's dashboard (:class:`abcwc.ui.dashboard.Dashboard`:
destinations, commands, a click on the map, stop; live) and the keyboard teleop panel
(:class:`abcwc.ui.teleop.TeleopPanel`)."""
