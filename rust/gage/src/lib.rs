//! Virtual-gage linear program with slacks (Ch. 5).
