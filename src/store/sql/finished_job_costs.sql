-- What every finished job cost: its id, the simulated time its run ended at, its wall seconds
-- (the attempt that finished plus any extensions) and whether its result converged (NULL
-- without a run-length policy).
-- no parameters
SELECT j.id, r.simulated_time, j.wall_seconds,
       json_extract(r.observables, '$.convergence.converged')
FROM jobs j JOIN results r ON r.job_id = j.id
WHERE j.status = 'done' AND j.wall_seconds IS NOT NULL
