-- The convergence verdict of each result as a column, so that the reports (`sweep status`,
-- `boundaries`, `plot`) read it without parsing the observables JSON of every result (issue 35).
-- 1: converged, 0: not converged, NULL: the result carries no verdict. The verdict is
-- `wetgran_core::observe::converged_in_json`: `convergence.converged` where the observables
-- have that key, else `stationarity.stationary`, each only where it is a JSON boolean. New
-- results get it from that function when they are inserted (store/sql/insert_result.sql); the
-- results already stored get it here, by the same rule written in SQL (json_type gives SQL NULL
-- for a missing key and the text 'null' for a JSON null, which, like the Rust function, does not
-- fall back to the stationarity check). An unreadable observables text keeps NULL.
ALTER TABLE results ADD COLUMN converged INTEGER CHECK (converged IS NULL OR converged IN (0, 1));

UPDATE results SET converged =
    CASE
        WHEN json_type(observables, '$.convergence.converged') IS NOT NULL THEN
            CASE json_type(observables, '$.convergence.converged')
                WHEN 'true' THEN 1 WHEN 'false' THEN 0 END
        ELSE
            CASE json_type(observables, '$.stationarity.stationary')
                WHEN 'true' THEN 1 WHEN 'false' THEN 0 END
    END
WHERE json_valid(observables);

-- What the reports read of each result and each job, as covering indexes
-- (store/sql/sweep_point_summaries.sql names them with INDEXED BY): reading `wall_seconds` or
-- `trend` from the table row means walking the overflow pages of the observables stored before
-- them (a 7 kB result spans two more pages, a 150 kB one about forty), and a job's start mode is
-- inside its spec. The index rows hold the columns themselves; `jobs_report` also serves the
-- time spent per sweep (store/sql/time_spent.sql: the wall seconds of its finished jobs).
CREATE INDEX results_report ON results (job_id, phase, wall_seconds, trend, converged);
CREATE INDEX jobs_report ON jobs (id, status, attempts, last_error, wall_seconds,
    json_extract(spec, '$.scene.initial.start'));
