"""Per-event front end of EV-Pose: consistency noise filter, separated-polarity time surface, temporal distance field."""
