-- Deletes a sweep's grid points before re-registering it (refined ones too if its file changed).
-- ?1: sweep id, ?2: whether the sweep file changed (all points go), ?3: REFINED_FROM, ?4: replicas
DELETE FROM sweep_points
WHERE sweep_id = ?1 AND (?2 OR (point < ?3 AND replica < ?4))
