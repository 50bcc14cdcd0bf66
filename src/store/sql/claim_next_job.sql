-- Claims the next claimable pending job of a sweep; returns its id and spec. Order: jobs that
-- pending continuation jobs wait for (a chain's next link) first, so chains start and advance
-- as early as possible; then grid order.
-- ?1: owner, ?2: now, ?3: sweep id
UPDATE jobs SET status = 'running', owner = ?1, heartbeat = ?2, claimed_at = ?2,
    attempts = attempts + 1
WHERE id = (SELECT j.id FROM sweep_points p JOIN jobs j ON j.id = p.job_id
            WHERE p.sweep_id = ?3 AND j.status = 'pending'
              AND (json_extract(j.spec, '$.start_from') IS NULL
                   OR EXISTS (SELECT 1 FROM jobs d
                              WHERE d.id = json_extract(j.spec, '$.start_from')
                                AND d.status IN ('done', 'failed')))
            ORDER BY EXISTS (SELECT 1 FROM jobs c
                             WHERE json_extract(c.spec, '$.start_from') = j.id
                               AND c.status = 'pending') DESC,
                     p.point, p.replica
            LIMIT 1)
  AND status = 'pending'
RETURNING id, spec
