-- Records the grid points skip_invalid left out of a sweep.
-- ?1: sweep id, ?2: left-out points (JSON)
UPDATE sweeps SET left_out = ?2 WHERE id = ?1
