-- Sets a sweep's update time.
-- ?1: sweep id, ?2: updated at
UPDATE sweeps SET updated_at = ?2 WHERE id = ?1
