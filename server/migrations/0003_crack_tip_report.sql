-- The path-independence report and the crack-opening K (extra crack_tips.csv columns, at
-- the end). NULL for rows written before: read back as NaN (null in the API).
ALTER TABLE crack_tips ADD COLUMN j1_half REAL;
ALTER TABLE crack_tips ADD COLUMN j2_half REAL;
ALTER TABLE crack_tips ADD COLUMN j1_double REAL;
ALTER TABLE crack_tips ADD COLUMN j2_double REAL;
ALTER TABLE crack_tips ADD COLUMN k1_cod REAL;
ALTER TABLE crack_tips ADD COLUMN k2_cod REAL;
