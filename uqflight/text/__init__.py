"""Text in and out: what the command line prints (`console`), how figures name outputs and parameters
(`labels`), strict JSON laid out for reading (`json_text`), and text files read within a bound
(`bounded`); the user's input refused (`Refusal`), and a value refused at a field (`FieldError`)."""


class Refusal(ValueError):
    """The user's input (a file, a campaign, an option, data) refused: the message is the whole line the user
    sees, naming the file and the field and saying what to do. The command line prints it as "error: MESSAGE"
    and exits 2 (`uqflight.cli.commands.RefusingGroup`). A refusal that is also a missing file or a failed
    build derives from that standard error too (`simulators.aircraft.AircraftNotFound`)."""


class FieldError(Refusal):
    """A value refused at a field of the campaign (`field`, a dotted path such as `design.level`), with what
    was expected (`message`); its text is "FIELD: MESSAGE". `campaign.schema.CampaignError` adds the file."""

    def __init__(self, field: str, message: str):
        self.field, self.message = field, message
        super().__init__(f"{field}: {message}" if field else message)
