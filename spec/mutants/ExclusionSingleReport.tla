------------------------ MODULE ExclusionSingleReport ------------------------
(***************************************************************************)
(* Mutant of Exclusion: the Master excludes on one declaration, its own or *)
(* one Observer's (the rule before fault model 2). A partly deaf Observer *)
(* then gets a healthy node excluded alone. TLC must report                *)
(* NoFalseExclusionInv violated (exit 12).                                 *)
(***************************************************************************)
EXTENDS MCExclusion

OneDeclaration(n) == 1

MutantSpec == Init /\ [][NextBy(Counts, OneDeclaration)]_vars
=============================================================================
