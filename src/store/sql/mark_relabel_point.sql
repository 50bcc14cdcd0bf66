-- Marks a job newly added to a sweep as not yet relabelled in that sweep when it already has a
-- result (a job shared with another sweep): its result joins this sweep's lines.
-- ?1: sweep id, ?2: job id
INSERT OR IGNORE INTO meta (key, value)
SELECT 'relabel:' || ?1 || ':' || ?2, '' WHERE EXISTS (SELECT 1 FROM results WHERE job_id = ?2)
