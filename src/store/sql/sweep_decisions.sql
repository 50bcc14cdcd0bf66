-- The decision record (`results.decided_on`) of every result of a sweep, for the criterion
-- that decided each label (`Store::decisions`). The record precedes the observables in the
-- row, so their pages are not read.
-- ?1: sweep id
SELECT p.job_id, r.decided_on
FROM sweep_points p
JOIN results r ON r.job_id = p.job_id
WHERE p.sweep_id = ?1 AND r.decided_on IS NOT NULL
