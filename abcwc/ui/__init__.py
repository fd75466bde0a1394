"""Notebook panels (ipywidgets): the keyboard teleop panel
(:class:`abcwc.ui.teleop.TeleopPanel`) and the navigator's click-the-map panel
(:class:`abcwc.ui.navigator_panel.NavigatorPanel`)."""
