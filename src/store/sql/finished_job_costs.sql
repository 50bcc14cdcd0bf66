-- What every finished job cost: its id, the simulated time its run ended at, its wall seconds
-- (the attempt that finished plus any extensions) and the verdict on its label (NULL for a
-- result stored before verdicts).
-- no parameters
SELECT j.id, r.simulated_time, j.wall_seconds, r.verdict
FROM jobs j JOIN results r ON r.job_id = j.id
WHERE j.status = 'done' AND j.wall_seconds IS NOT NULL
