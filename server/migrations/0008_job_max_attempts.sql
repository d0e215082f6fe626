-- A job's own retry budget (`max_attempts` of `POST /api/v1/jobs` and of a sweep): claims
-- before a lost worker fails the job. NULL: the server's `--max-attempts`.
ALTER TABLE jobs ADD COLUMN max_attempts INTEGER;
