"""The guided RAPID program (``rapid generate --guided``): the operator jogs, the program in the motion task
asks the PC what it needs, prompts on the FlexPendant, stops, and on Start sends where the arm stands.

An IRC5 does not jog while a program runs in the motion task, so the PC cannot watch the joints while
the operator jogs (that needs a background task, option 623-1 Multitasking). ``HeGuide`` does what
ABB's own "learn position" routines do, with no option at all:

1. ``READY``: wait for the PC's ``GUIDE verdict hint`` (line protocol) or ``guide_verdict`` /
   ``guide_hint`` registers (Modbus): the verdict on the posture sent last and what the set still lacks;
2. ``PROMPT``: show both on the pendant (``TPWrite``; then ``TPReadFK`` with the keys *Capture* and
   *Done*, or on RobotWare 6/7 ``UIMessageBox`` with the same two buttons: ``guided.prompt``);
3. *Capture*: ``JOG``, ``Stop \\NoRegain;`` - the operator jogs in manual mode with the enabling
   device and presses Start; execution continues after the ``Stop``;
4. ``AT k``: the k-th posture the operator offered; the PC reads ``CJointT()`` and
   ``CRobT(\\Tool:=tool0 \\WObj:=wobj0)`` through the link (``JOINTS``, ``POSE``, ``QUAT``), grabs,
   judges and acknowledges (``ACK k``), then sends the verdict with the next hint (back to 1);
5. *Done*: ``DONE``; the program serves the link until a PC sends ``GUIDE`` again (a resumed capture).

The program holds no jointtarget and never moves the robot (``HE_COUNT`` is 0: ``GOTO`` is refused).
This module holds the one table of verdicts and hints both sides use: the PC sends the codes
(``src/handeye/drivers/controller/protocol.py`` carries them), the program shows their texts.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Verdict", "VERDICTS", "VERDICT_CODES", "HINTS", "HINT_CODES", "PROMPTS", "GUIDED_PROGRAM",
           "GUIDE_MODULE", "FK_CAPTURE", "FK_DONE", "hint_text", "verdict_text", "hint_code_for"]

#: The program name the guided program answers to ``VERSION`` (the planned one answers ``RAPID``).
GUIDED_PROGRAM = "GUIDE"
#: The guided main module.
GUIDE_MODULE = "HeGuide"
#: How the program asks the operator: ``fk`` (``TPReadFK``: S4C+, RobotWare 5/6/7), ``messagebox``
#: (``UIMessageBox``: RobotWare 6/7 only).
PROMPTS = ("fk", "messagebox")
#: The function keys (TPReadFK answers 1..5) of the two answers.
FK_CAPTURE, FK_DONE = 1, 5


@dataclass(frozen=True)
class Verdict:
    """The PC's word on the posture the operator offered last."""

    code: int
    name: str
    text: str  # on the pendant (at most 40 characters: one pendant line)


VERDICTS = (
    Verdict(1, "START", "handeye: guided capture"),
    Verdict(2, "CAPTURED", "captured"),
    Verdict(3, "TOO_CLOSE", "not captured: too close to an earlier"),
    Verdict(4, "NOT_SEEN", "not captured: board not seen"),
    Verdict(5, "GOOD_ENOUGH", "captured: GOOD ENOUGH, press Done"),
    Verdict(6, "NEAR_VOLUME", "not captured: near a keep-out volume"),
)
VERDICT_CODES = {v.name: v.code for v in VERDICTS}

_CELLS = ("upper left", "upper middle", "upper right", "middle left", "centre", "middle right", "lower left",
          "lower middle", "lower right")
#: Hint code -> pendant text (at most 40 characters). 0: nothing missing.
HINTS = {0: "nothing missing: Done, or capture more", 1: "capture more postures",
         2: "turn the flange about tool0 x", 3: "turn the flange about tool0 y",
         4: "turn the flange about tool0 z (axis 6)", 5: "turn further between postures",
         6: "go nearer to / farther from the board"}
HINTS.update({7 + i: f"board in the {name} of the image" for i, name in enumerate(_CELLS)})
HINT_CODES = tuple(sorted(HINTS))


def verdict_text(code: int) -> str:
    return {v.code: v.text for v in VERDICTS}[code]


def hint_text(code: int) -> str:
    return HINTS[code]


def hint_code_for(word: str, advice: str) -> int:
    """The hint code of one missing quality word (``station.guided.capture.Missing``: its word and advice)."""
    if word == "postures":
        return 1
    if "about tool0" in advice:
        for axis, code in (("tool0 x", 2), ("tool0 y", 3), ("tool0 z", 4)):
            if axis in advice:
                return code
        return 5
    if "further" in advice or "turn" in advice:
        return 5
    if word == "distance spread":
        return 6
    if "image" in advice:
        for i, name in enumerate(_CELLS):
            if name in advice or (name == "centre" and "middle of" in advice):
                return 7 + i
    return 1


# ---------------------------------------------------------------------------------------- RAPID text
_LINE_CASE = '''    CASE "GUIDE":
      IF HeArgs(2) THEN
        HeGuideRequest id;
      ENDIF
'''
_LINE_STATES = '''    CASE HE_PROMPT:
      RETURN "PROMPT";
    CASE HE_JOG:
      RETURN "JOG";
    CASE HE_DONE:
      RETURN "DONE";
'''
_LINE_PROCS = '''
  PROC HeGuideRequest(string id)
    ! GUIDE verdict hint (READY or DONE): the PC's verdict on the posture offered last, the next hint.
    IF (heState <> HE_READY) AND (heState <> HE_DONE) THEN
      heReply := id + " ERR 5 busy: ACK posture " + NumToStr(hePosture, 0) + " first";
    ELSEIF (heArg{1} <> Round(heArg{1})) OR (heArg{2} <> Round(heArg{2})) THEN
      heReply := id + " ERR 3 verdict and hint must be integers";
    ELSE
      heVerdict := heArg{1};
      heHint := heArg{2};
      heTarget := -1;
      heReply := id + " OK " + NumToStr(hePosture, 0);
    ENDIF
  ENDPROC

  PROC HeLinkWaitGuide()
    ! READY or DONE: serve requests until the PC sends GUIDE (it sets heTarget).
    heTarget := 0;
    HeIdleRestart;
    WHILE heTarget = 0 DO
      HeServeOne WAIT_MAX;
    ENDWHILE
  ENDPROC

  PROC HeLinkState()
    ! Nothing to publish: STATUS replies heState (a line is not served while the pendant prompts or
    ! the program is stopped; the PC's request waits).
  ENDPROC
'''
_IO_PROCS = '''  PROC HeLinkWaitGuide()
    ! READY or DONE: wait for the PC's verdict (giHeGuide <> 0, its hint in giHeHint) or new tool data.
    heTarget := 0;
    SetDO doHeAtPosture, 0;
    SetGO goHePosture, hePosture;
    SetGO goHeState, heState;
    WHILE heTarget = 0 DO
      WaitUntil GInput(giHeGuide) <> 0 OR GInput(giHeToolCmd) <> heToolSeq;
      IF GInput(giHeToolCmd) <> heToolSeq THEN
        HeApplyTool;
      ELSE
        heHint := GInput(giHeHint);
        heVerdict := GInput(giHeGuide);
        heTarget := -1;
      ENDIF
    ENDWHILE
  ENDPROC

  PROC HeLinkState()
    ! Publish the guided program's state (PROMPT, JOG) for the PC.
    SetGO goHeState, heState;
  ENDPROC

'''
#: Signals the guided HeIo reads besides the planned one's (``src/handeye/drivers/controller/modbus_map.yaml``).
GUIDED_IO_SIGNALS = ("giHeGuide", "giHeHint")

_FK_PROMPT = '''    TPReadFK heKey, "Capture: jog there, then Start. Done: end.", "Capture", stEmpty, stEmpty, stEmpty, "Done";'''
_BOX_DATA = '''  VAR string heButtons{2} := ["Capture", "Done"];
  VAR string heLines{3};'''
_BOX_PROMPT = '''    heLines{1} := HeVerdictText();
    heLines{2} := "next: " + HeHintText();
    heLines{3} := "Capture: jog there, then press Start";
    heKey := UIMessageBox(\\Header:="handeye guided capture" \\MsgArray:=heLines \\BtnArray:=heButtons);
    IF heKey = 2 THEN
      heKey := HE_FK_DONE;
    ENDIF'''


def link_fields(guided: bool) -> dict:
    """The fields of the link templates that add the guided program's requests (empty when planned)."""
    if not guided:
        return {"guide_case": "", "guide_states": "", "guide_line_procs": "", "guide_io_procs": ""}
    return {"guide_case": _LINE_CASE, "guide_states": _LINE_STATES, "guide_line_procs": _LINE_PROCS,
            "guide_io_procs": _IO_PROCS}


def _cases(table: dict) -> str:
    return "\n".join(f'    CASE {code}:\n      RETURN "{text}";' for code, text in sorted(table.items()))


def guide_fields(prompt: str) -> dict:
    """The fields of ``HeGuide.mod.tmpl`` for a prompt style (:data:`PROMPTS`)."""
    if prompt not in PROMPTS:
        raise ValueError(f"guided.prompt must be one of {', '.join(PROMPTS)}; got {prompt!r}")
    box = prompt == "messagebox"
    return {"fk_done": FK_DONE, "prompt_data": _BOX_DATA if box else "", "prompt": _BOX_PROMPT if box else _FK_PROMPT,
            "verdicts": _cases({v.code: v.text for v in VERDICTS}), "hints": _cases(HINTS)}
