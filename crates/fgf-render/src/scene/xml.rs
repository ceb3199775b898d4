//! Mitsuba 3 XML loader (issue 4): XML -> [`super::desc::SceneDesc`].
