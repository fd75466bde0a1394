"""Notebook panels (ipywidgets): the rider's dashboard (:class:`abcwc.ui.dashboard.Dashboard`),
the keyboard teleop panel
(:class:`abcwc.ui.teleop.TeleopPanel`) and the navigator's click-the-map panel
(:class:`abcwc.ui.navigator_panel.NavigatorPanel`)."""
