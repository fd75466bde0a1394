"""nbgrader's settings for the abcwc course (written by `abcwc course build`)."""

c = get_config()  # noqa: F821 - nbgrader provides get_config in its config files

c.CourseDirectory.course_id = "abcwc"
# seconds a cell may run when nbgrader executes a submission (its default is 30); the
# longest cells of the worked chapters take about 75 s, more on a busy grading machine
c.Execute.timeout = 600
