// The fmpc rule language (docs/language.md). Layout-insensitive: newlines are whitespace and a variable's terms
// run until the next `input`, `output`, `rule` or `system`. Comments go to the hidden channel so that the
// formatter can put them back. A character the lexer cannot use becomes an ERROR_CHARACTER token (which no parser
// rule accepts, so ANTLR resynchronises after it) and a quoted name without its closing quote becomes a STRING
// token; compiler/frontend/fmpc_parser.cpp reports both itself, so no lexer error reaches ANTLR's console.
grammar Fmpc;

// A file is a flat list of items; the AST builder groups settings, variables and rules under the `system` line
// before them, and terms under the variable line before them. Keeping the list flat lets the parser resume at the
// next item after a syntax error (see FmpcErrorStrategy::recover), so later errors are reported too.
file : item* EOF ;

item : systemHeader | setting | variableDecl | termDecl | ruleDecl ;

systemHeader : SYSTEM name description=STRING? ;

setting
  : TYPE INTERVAL_TYPE2? value=name                            # typeSetting
  | TYPE_REDUCTION value=name                                  # typeReductionSetting
  | AND value=name                                             # andSetting
  | OR value=name                                              # orSetting
  | IMPLICATION value=name                                     # implicationSetting
  | AGGREGATION value=name                                     # aggregationSetting
  | DEFUZZIFY value=name (SAMPLES (count=NUMBER | EXACT))?     # defuzzifySetting
  | WHEN NO RULE FIRES ':' noFireAction                        # noFireSetting
  ;

noFireAction : MIDRANGE | VALUE NUMBER | ERROR ;

variableDecl : direction=(INPUT | OUTPUT) name description=STRING? IN '[' low=NUMBER ',' high=NUMBER ']' unit? ;

unit : name | '%' ;

// An interval type-2 term (docs/language.md): an interval argument `mean [7.1, 8.2]`, an explicit pair
// `upper gauss(...) lower gauss(...)`, or MATLAB's `lower scale 0.8 lag 0.1` after the MF.
termDecl : name IS UPPER? mfCall (LOWER (lowerMf=mfCall | lowerScaleLag))? ;

// Parameters are named. Positional ones, `gaussmf(0.91, 7.64)` or MATLAB's vector `gaussmf [0.91 7.64]`, are read
// so that sema can refuse them with the named spelling (docs/language.md, "MATLAB's names").
mfCall : family=name ('(' (argument (',' argument)*)? ')' | '[' (NUMBER ','?)* ']') ;

lowerScaleLag : SCALE scale=NUMBER (LAG lag=NUMBER)? | LAG lag=NUMBER ;

argument : name? (NUMBER | interval) unit? ;

interval : '[' low=NUMBER ',' high=NUMBER ']' ;

ruleDecl : RULE label=name? ':' IF clause (connective clause)* THEN clause (AND clause)* (WEIGHT weight=NUMBER)? ;

connective : AND | OR ;

clause : variableName=name IS NOT? hedge? termName=name ;

hedge : SOMEWHAT | VERY VERY? | EXTREMELY ;

// Words that are keywords only where a setting or a variable header expects them; anywhere a name is expected
// they are ordinary names (a term may be called `value` or `error`). The printer quotes only the reserved words.
name : IDENTIFIER | STRING | TYPE | IMPLICATION | AGGREGATION | DEFUZZIFY | SAMPLES | EXACT | WHEN | NO | FIRES
     | MIDRANGE | VALUE | ERROR | IN | TYPE_REDUCTION | UPPER | LOWER | SCALE | LAG ;

// Reserved words: a name spelled like one of these must be quoted. Keep them together, SYSTEM first and EXTREMELY
// last: FmpcErrorStrategy tests "is a reserved word" as a range of token types.
SYSTEM : 'system' ;
INPUT : 'input' ;
OUTPUT : 'output' ;
RULE : 'rule' ;
IF : 'if' ;
THEN : 'then' ;
IS : 'is' ;
NOT : 'not' ;
AND : 'and' ;
OR : 'or' ;
WEIGHT : 'weight' ;
SOMEWHAT : 'somewhat' ;
VERY : 'very' ;
INTERVAL_TYPE2 : 'interval_type2' ;
EXTREMELY : 'extremely' ;

// Contextual words (see `name`).
TYPE : 'type' ;
IMPLICATION : 'implication' ;
AGGREGATION : 'aggregation' ;
DEFUZZIFY : 'defuzzify' ;
SAMPLES : 'samples' ;
EXACT : 'exact' ;
WHEN : 'when' ;
NO : 'no' ;
FIRES : 'fires' ;
MIDRANGE : 'midrange' ;
VALUE : 'value' ;
ERROR : 'error' ;
IN : 'in' ;
TYPE_REDUCTION : 'type_reduction' ;
UPPER : 'upper' ;
LOWER : 'lower' ;
SCALE : 'scale' ;
LAG : 'lag' ;

NUMBER : '-'? DIGITS ('.' DIGITS)? ([eE] [+-]? DIGITS)? ;
IDENTIFIER : [A-Za-z_] [A-Za-z0-9_]* ;
STRING : '"' ~["\r\n]* '"' ;

COMMENT : '#' ~[\r\n]* -> channel(HIDDEN) ;
WHITESPACE : [ \t\r\n\f\uFEFF]+ -> skip ;
UNTERMINATED_STRING : '"' ~["\r\n]* -> type(STRING) ;
ERROR_CHARACTER : . ;

fragment DIGITS : [0-9]+ ;
