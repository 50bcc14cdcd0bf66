-- Records a job array about to be submitted; returns its id.
-- ?1: sweep id, ?2: dir, ?3: script, ?4: number of tasks, ?5: submitted at
INSERT INTO submissions (sweep_id, dir, script, tasks, submitted_at)
VALUES (?1, ?2, ?3, ?4, ?5) RETURNING id
